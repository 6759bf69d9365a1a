#include "cli_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "cli_args.hpp"
#include "kccd/overlay/recording/video_sink.hpp"

namespace kccd::cli {

void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected) {
  // A symbolic link: its target is locked (open and stat follow it) and replaced.
  // Lock the file, then make sure the name still refers to the locked file: a concurrent edit may
  // have renamed a new file into place while this one waited.
  int fd = -1;
  for (int attempt = 0;; ++attempt) {
    fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    struct stat locked {
    }, named{};
    if (flock(fd, LOCK_EX) != 0 || fstat(fd, &locked) != 0) {
      ::close(fd);
      throw UsageError(path + ": cannot lock the file for editing (" + std::strerror(errno) + ")");
    }
    if (::stat(path.c_str(), &named) == 0 && named.st_ino == locked.st_ino && named.st_dev == locked.st_dev) break;
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
  writeFileAtomically(path, edited);      // keeps the file's mode
}

void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& option) {
  overlay::writePngAtomically(path, image, option + " " + path);
}

}  // namespace kccd::cli
