// One YAML document, unique plain keys, bounded nesting: checked on the parser's event stream.
#include "kccd/yaml_document.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/exceptions.h>
#include <yaml-cpp/parser.h>

#include <set>
#include <sstream>
#include <vector>

#include "kccd/input_error.hpp"

namespace kccd {
namespace {

// The place of `mark` in `source` (no line when the mark has none).
InputLocation at(const std::string& source, const YAML::Mark& mark, std::string field) {
  InputLocation where{source, 0, 0, std::move(field)};
  if (mark.line >= 0) {
    where.line = static_cast<std::size_t>(mark.line) + 1;
    where.column = static_cast<std::size_t>(mark.column) + 1;
  }
  return where;
}

class Checker final : public YAML::EventHandler {
 public:
  Checker(const std::string& source, const YamlLimits& limits) : source_(source), limits_(limits) {}

  void OnDocumentStart(const YAML::Mark& mark) override {
    if (++documents_ > 1)
      fail(mark, "document",
           "a second YAML document ('---' or '...' followed by more): the file must hold exactly one");
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    count(mark, 1);
    named(anchor, 1);
    leaf(mark, "~", true);
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    for (const Frame& f : stack_)
      if (f.anchor == anchor && anchor != 0) fail(mark, path(), "an alias inside the node it names (a cycle)");
    count(mark, anchor < sizes_.size() ? sizes_[anchor] : 1);
    leaf(mark, "", false);
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string& value) override {
    count(mark, 1);
    named(anchor, 1);
    leaf(mark, value, true);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    count(mark, 1);
    open(mark, false, anchor);
  }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    count(mark, 1);
    open(mark, true, anchor);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapEnd() override { close(); }

 private:
  struct Frame {
    bool map = false;
    bool expect_key = true;  // maps: the next node is a key
    std::size_t index = 0;   // sequences: index of the next item
    std::string key;         // maps: the key of the value being read
    std::set<std::string> keys;
    YAML::anchor_t anchor = 0;   // the anchor naming this node (0: none)
    std::size_t first_node = 0;  // expanded_ when it opened
  };

  // `nodes` more nodes read (an alias: as many as the node it names holds).
  void count(const YAML::Mark& mark, std::size_t nodes) {
    expanded_ += nodes;
    if (expanded_ > limits_.max_expanded_nodes)
      fail(mark, path(),
           "aliases expand the document to more than " + std::to_string(limits_.max_expanded_nodes) +
               " values (anchors and aliases are for sharing a little, not for multiplying)");
  }

  // Remembers the size of the node an anchor names.
  void named(YAML::anchor_t anchor, std::size_t nodes) {
    if (anchor == 0) return;
    if (sizes_.size() <= anchor) sizes_.resize(anchor + 1, 1);
    sizes_[anchor] = nodes;
  }

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& field, const std::string& problem) const {
    throw InputError(at(source_, mark, field.empty() ? std::string("document") : field), problem);
  }

  std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < stack_.size(); ++i) {
      const Frame& f = stack_[i];
      if (f.map) {
        if (f.expect_key) break;  // no key read yet
        if (!p.empty()) p += '.';
        p += printable(f.key, 40);
      } else {
        p += '[' + std::to_string(f.index) + ']';
      }
    }
    return p;
  }

  // A node that is a key of the innermost mapping is checked here; returns true when it was one.
  bool key(const YAML::Mark& mark, const std::string& value, bool plain) {
    if (stack_.empty() || !stack_.back().map || !stack_.back().expect_key) return false;
    Frame& f = stack_.back();
    if (!plain) fail(mark, path(), "a mapping key must be a plain value (no alias, list or mapping)");
    if (!f.keys.insert(value).second) {
      f.key = value;
      f.expect_key = false;
      fail(mark, path(), "duplicate key '" + printable(value, 40) + "' (YAML keys are unique: which value was meant?)");
    }
    f.key = value;
    f.expect_key = false;
    return true;
  }

  // A value (or sequence item) has been read completely.
  void done() {
    if (stack_.empty()) return;
    Frame& f = stack_.back();
    if (f.map)
      f.expect_key = true;
    else
      ++f.index;
  }

  void leaf(const YAML::Mark& mark, const std::string& value, bool plain) {
    if (!key(mark, value, plain)) done();
  }

  void open(const YAML::Mark& mark, bool map, YAML::anchor_t anchor) {
    key(mark, "", false);  // a list or mapping as a key fails there
    if (static_cast<int>(stack_.size()) >= limits_.max_depth)
      fail(mark, path(), "nested deeper than " + std::to_string(limits_.max_depth) + " levels");
    Frame f;
    f.map = map;
    f.anchor = anchor;
    f.first_node = expanded_ - 1;
    stack_.push_back(std::move(f));
  }

  void close() {
    if (!stack_.empty()) {
      named(stack_.back().anchor, expanded_ - stack_.back().first_node);
      stack_.pop_back();
    }
    done();
  }

  const std::string& source_;
  const YamlLimits& limits_;
  int documents_ = 0;
  std::vector<Frame> stack_;
  std::size_t expanded_ = 0;        // nodes read, aliases counted as copies
  std::vector<std::size_t> sizes_;  // per anchor, the nodes its node holds
};

}  // namespace

void checkYamlDocument(std::string_view text, const std::string& source, const YamlLimits& limits) {
  if (text.size() > limits.max_bytes)
    throw InputError({source, 0, 0, "file"}, "larger than " + std::to_string(limits.max_bytes >> 20) + " MiB");
  std::istringstream in{std::string(text)};
  Checker checker(source, limits);
  try {
    YAML::Parser parser(in);
    while (parser.HandleNextDocument(checker)) {
    }
  } catch (const YAML::Exception& e) {
    throw InputError(at(source, e.mark, {}), "YAML syntax error: " + printable(e.msg, 120));
  }
}

}  // namespace kccd
