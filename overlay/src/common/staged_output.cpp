#include "kccd/overlay/common/staged_output.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <system_error>
#include <utility>

namespace kccd::overlay {
namespace fs = std::filesystem;

namespace {

std::string errnoText(int e) { return std::strerror(e); }

// Where a write to `path` must land: the final target of a chain of symbolic links (so a link
// stays a link), or `path` itself.
fs::path finalTarget(const fs::path& path) {
  std::error_code ec;
  fs::path p = path;
  for (int hops = 0; hops < 40 && fs::is_symlink(p, ec); ++hops) {
    const fs::path link = fs::read_symlink(p, ec);
    if (ec) break;
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  return p;
}

fs::path folderOf(const fs::path& p) { return p.parent_path().empty() ? fs::path(".") : p.parent_path(); }

// A hidden name beside `target`: ".NAME" + `suffix` (a mkstemp/mkdtemp template).
std::string hiddenBeside(const fs::path& target, const std::string& name, const std::string& suffix) {
  std::string hidden(1, '.');
  hidden += name;
  hidden += suffix;
  return (folderOf(target) / hidden).string();
}

// The target without a trailing separator ("out/" names the folder "out").
fs::path withoutTrailingSeparator(fs::path p) {
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

}  // namespace

unsigned plainCreateMode(bool folder) {
  const mode_t mask = ::umask(0);  // read by setting; restored at once
  ::umask(mask);
  return (folder ? 0777u : 0666u) & ~static_cast<unsigned>(mask);
}

StagedOutput::StagedOutput(const fs::path& target, Kind kind, std::string label, Existing existing)
    : target_(finalTarget(withoutTrailingSeparator(target))),
      label_(std::move(label)),
      kind_(kind),
      existing_(existing) {
  if (label_.empty()) label_ = target.string();
  const fs::path dir = folderOf(target_);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw OutputError(label_ + ": folder " + dir.string() + " does not exist");
  if (kind_ == Kind::File) {
    const std::string ext = target_.extension().string();
    std::string name = hiddenBeside(target_, target_.stem().string(), ".kccd-XXXXXX" + ext);
    const int fd = ::mkstemps(name.data(), static_cast<int>(ext.size()));
    if (fd < 0) throw OutputError(label_ + ": cannot write in " + dir.string() + " (" + errnoText(errno) + ")");
    ::close(fd);
    temp_ = name;
  } else {
    if (fs::exists(target_, ec)) {
      if (!fs::is_directory(target_, ec)) throw OutputError(label_ + ": exists and is not a folder");
      if (existing_ == Existing::KeepFolder && !fs::is_empty(target_, ec))
        throw OutputError(label_ + ": the folder is not empty (kccd does not mix runs)");
    }
    std::string name = hiddenBeside(target_, target_.filename().string(), ".kccd-XXXXXX");
    if (::mkdtemp(name.data()) == nullptr)
      throw OutputError(label_ + ": cannot create a folder in " + dir.string() + " (" + errnoText(errno) + ")");
    temp_ = name;
  }
}

StagedOutput::~StagedOutput() {
  if (committed_ || temp_.empty()) return;
  std::error_code ec;
  fs::remove_all(temp_, ec);
}

void StagedOutput::commit() {
  if (committed_) return;
  std::error_code ec;
  if (kind_ == Kind::File) {
    struct stat st {};
    const unsigned mode = ::stat(target_.c_str(), &st) == 0 ? (st.st_mode & 07777) : plainCreateMode(false);
    const int fd = ::open(temp_.c_str(), O_RDONLY | O_CLOEXEC);
    bool ok = fd >= 0 && ::fchmod(fd, mode) == 0 && ::fsync(fd) == 0;
    const int err = errno;
    if (fd >= 0) ::close(fd);
    if (!ok) throw OutputError(label_ + ": write failed (" + errnoText(err) + ")");
    if (std::rename(temp_.c_str(), target_.c_str()) != 0)
      throw OutputError(label_ + ": cannot replace the file (" + errnoText(errno) + ")");
    committed_ = true;
    return;
  }
  if (::chmod(temp_.c_str(), plainCreateMode(true)) != 0)
    throw OutputError(label_ + ": cannot set the folder's permissions (" + errnoText(errno) + ")");
  fs::path aside;
  if (fs::exists(target_, ec)) {
    if (!fs::is_directory(target_, ec)) throw OutputError(label_ + ": exists and is not a folder");
    if (fs::is_empty(target_, ec)) {
      fs::remove(target_, ec);
    } else if (existing_ == Existing::ReplaceFolder) {
      std::string name = hiddenBeside(target_, target_.filename().string(), ".old-XXXXXX");
      if (::mkdtemp(name.data()) == nullptr || std::rename(target_.c_str(), name.c_str()) != 0)
        throw OutputError(label_ + ": cannot move the old folder aside (" + errnoText(errno) + ")");
      aside = name;
    } else {
      throw OutputError(label_ + ": the folder is not empty (kccd does not mix runs)");
    }
  }
  if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
    const int e = errno;
    if (!aside.empty()) std::rename(aside.c_str(), target_.c_str());
    throw OutputError(label_ + ": cannot move the new folder into place (" + errnoText(e) + ")");
  }
  committed_ = true;
  if (!aside.empty()) fs::remove_all(aside, ec);
}

void writeFileAtomically(const fs::path& path, const std::string& bytes, const std::string& label) {
  const std::string shown = label.empty() ? path.string() : label;
  StagedOutput out(path, StagedOutput::Kind::File, shown);
  const int fd = ::open(out.path().c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) throw OutputError(shown + ": cannot write (" + errnoText(errno) + ")");
  std::size_t done = 0;
  bool ok = true;
  while (ok && done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) done += static_cast<std::size_t>(n);
  }
  const int err = errno;
  ::close(fd);
  if (!ok) throw OutputError(shown + ": write failed (" + errnoText(err) + ")");
  out.commit();
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void checkOutputPath(const std::string& path, const std::string& option, const std::string& extension) {
  if (lowerExtension(path) != extension)
    throw OutputError(option + " " + path + ": the output must be a " + extension + " file");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw OutputError(option + " " + path + ": directory " + dir.string() + " does not exist");
}

bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  return std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec) && std::filesystem::equivalent(a, b, ec);
}

}  // namespace kccd::overlay
