#include "cli_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "cli_args.hpp"

namespace kccd::cli {

Model loadOrExplain(const std::string& path, std::string* text) {
  try {
    if (text == nullptr) return loadModel(path);
    *text = readModelText(path);
    return parseModel(*text, path);
  } catch (const InputError& e) {
    throw UsageError(e.what());
  }
}

namespace {

// Where a write to `path` must land: the final target of a chain of symbolic links (so a link
// stays a link), or `path` itself.
std::filesystem::path writeTarget(const std::string& path) {
  std::error_code ec;
  std::filesystem::path p = path;
  for (int hops = 0; hops < 40 && std::filesystem::is_symlink(p, ec); ++hops) {
    const std::filesystem::path link = std::filesystem::read_symlink(p, ec);
    if (ec) break;
    p = link.is_absolute() ? link : p.parent_path() / link;
  }
  return p;
}

// Writes `text` to a new unique file beside `target` with `mode`, then renames it over `target`.
void replaceFile(const std::filesystem::path& target, const std::string& shown, const std::string& text, mode_t mode) {
  const std::filesystem::path dir = target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  std::string tmp = (dir / ("." + target.filename().string() + ".kccd-XXXXXX")).string();
  const int fd = mkstemp(tmp.data());
  if (fd < 0) throw UsageError(shown + ": cannot write (" + std::strerror(errno) + ")");
  bool ok = fchmod(fd, mode) == 0;
  std::size_t done = 0;
  while (ok && done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) done += static_cast<std::size_t>(n);
  }
  const int err = ok ? 0 : errno;
  ok = ok && fsync(fd) == 0;
  ok = (::close(fd) == 0) && ok;
  if (!ok) {
    std::remove(tmp.c_str());
    throw UsageError(shown + ": write failed (" + std::strerror(err != 0 ? err : errno) + ")");
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const int e = errno;
    std::remove(tmp.c_str());
    throw UsageError(shown + ": cannot replace the file (" + std::strerror(e) + ")");
  }
}

mode_t newFileMode() {
  const mode_t mask = umask(0);
  umask(mask);
  return 0666 & ~mask;
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& text) {
  const std::filesystem::path target = writeTarget(path);
  struct stat st {};
  const mode_t mode = ::stat(target.c_str(), &st) == 0 ? (st.st_mode & 07777) : newFileMode();
  replaceFile(target, path, text, mode);
}

void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected) {
  const std::filesystem::path target = writeTarget(path);
  // Lock the file, then make sure the name still refers to the locked file: a concurrent edit may
  // have renamed a new file into place while this one waited.
  int fd = -1;
  for (int attempt = 0;; ++attempt) {
    fd = ::open(target.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    struct stat locked {}, named {};
    if (flock(fd, LOCK_EX) != 0 || fstat(fd, &locked) != 0) {
      ::close(fd);
      throw UsageError(path + ": cannot lock the file for editing (" + std::strerror(errno) + ")");
    }
    if (::stat(target.c_str(), &named) == 0 && named.st_ino == locked.st_ino && named.st_dev == locked.st_dev) break;
    ::close(fd);
    if (attempt > 1000) throw UsageError(path + ": the file keeps being replaced; edit not done");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }  // also releases the lock
  } closer{fd};
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
  }
  if (expected != nullptr && text != *expected)
    throw UsageError(path + ": the file changed while kccd worked on it; nothing written (run again)");
  const std::string edited = edit(text);  // an EditError names the file and place itself
  struct stat st {};
  replaceFile(target, path, edited, fstat(fd, &st) == 0 ? (st.st_mode & 07777) : newFileMode());
}

void checkOutputPath(const std::string& path, const std::string& option, const std::string& extension) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext != extension) throw UsageError(option + " " + path + ": the output must be a " + extension + " file");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw UsageError(option + " " + path + ": directory " + dir.string() + " does not exist");
}

void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& option) {
  std::vector<uchar> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw UsageError(option + " " + path + ": cannot encode the image");
  writeFileAtomically(path, std::string(png.begin(), png.end()));
}

}  // namespace kccd::cli
