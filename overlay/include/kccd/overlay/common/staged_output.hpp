// Outputs that appear whole or not at all: written under a temporary name beside their target,
// moved into place by one rename when everything is written. Every writer of the suite (model
// edits, reports, videos, PNG folders, synthetic recordings) goes through this unit.
#pragma once

#include <filesystem>
#include <string>

#include "kccd/input_error.hpp"

namespace kccd::overlay {

/// An output that cannot be staged, written or moved into place. One line naming the output as
/// the user gave it ("-o out.mp4: cannot write in out (Permission denied)").
class OutputError : public InputError {
 public:
  using InputError::InputError;
};

/// The permission bits a plain create would give under the process's umask: 0666 & ~umask for a
/// file, 0777 & ~umask for a folder.
unsigned plainCreateMode(bool folder);

/// One output file or folder being written under a temporary name in the target's folder (same
/// file system, so the final rename is atomic). Destroying it without commit() removes what was
/// written; a target that exists is untouched until commit().
class StagedOutput {
 public:
  enum class Kind { File, Folder };
  /// What commit() does with a target that already exists: a file is always replaced (keeping its
  /// permission bits); a folder is replaced if empty, otherwise only with ReplaceFolder.
  enum class Existing { KeepFolder, ReplaceFolder };

  /// Reserves a unique temporary name beside `target` (a file keeps its extension, so writers
  /// that choose the format by it still do). `label` is how errors name the output ("-o x.mp4").
  /// A symbolic link as target stays a link: its final target is replaced. Throws OutputError.
  StagedOutput(const std::filesystem::path& target, Kind kind, std::string label,
               Existing existing = Existing::KeepFolder);
  ~StagedOutput();
  StagedOutput(const StagedOutput&) = delete;
  StagedOutput& operator=(const StagedOutput&) = delete;

  /// Where to write now: the temporary file (created empty) or folder (created empty).
  const std::filesystem::path& path() const { return temp_; }
  /// The path the output will have after commit().
  const std::filesystem::path& target() const { return target_; }

  /// Gives the output the permissions a plain create would (a replaced file keeps its own), makes
  /// a file's bytes durable (fsync), and renames it into place; a replaced non-empty folder is
  /// moved aside first and removed after. Throws OutputError and leaves the target as it was.
  void commit();

 private:
  std::filesystem::path target_, temp_;
  std::string label_;
  Kind kind_;
  Existing existing_;
  bool committed_ = false;
};

/// The extension of `path` in lower case, with its dot (".mp4"; empty when none).
std::string lowerExtension(const std::string& path);

/// Checks an output path before any work: its extension (lower-cased) is `extension` and its folder
/// exists. Throws OutputError "<option> <path>: ..." (`option` names it, e.g. "-o").
void checkOutputPath(const std::string& path, const std::string& option, const std::string& extension);

/// Whether two paths name one existing file (a link, another spelling).
bool sameFile(const std::string& a, const std::string& b);

/// Writes `bytes` to `path` through a StagedOutput: readers never see a partial file, a symbolic
/// link stays a link, an existing file keeps its mode, a new one gets plainCreateMode. `label`
/// names the output in errors (default: the path). Throws OutputError.
void writeFileAtomically(const std::filesystem::path& path, const std::string& bytes, const std::string& label = "");

}  // namespace kccd::overlay
