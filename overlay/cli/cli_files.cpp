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

void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected) {
  // A symbolic link: its target is locked (open and stat follow it) and replaced.
  // Lock the file, then make sure the name still refers to the locked file: a concurrent edit may
  // have renamed a new file into place while this one waited.
  int fd = -1;
  for (int attempt = 0;; ++attempt) {
    fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw UsageError(path + ": cannot read the file (" + std::strerror(errno) + ")");
    struct stat locked {}, named {};
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
  writeFileAtomically(path, edited);  // keeps the file's mode
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
  writeFileAtomically(path, std::string(png.begin(), png.end()), option + " " + path);
}

bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  return std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec) && std::filesystem::equivalent(a, b, ec);
}

}  // namespace kccd::cli
