#include "yaml_input.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace kccd::calib::detail {

std::string readInputFile(const std::string& path, std::size_t max_bytes, const char* what) {
  const auto fail = [&](const std::string& problem) -> void { throw InputError(path + ": file: " + problem); };
  const std::string too_large = std::string("larger than ") + std::to_string(max_bytes >> 10) + " KiB";
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int err = errno;
    fail(std::string("cannot open the ") + what + " (" + (err == ENOENT ? "no such file" : std::strerror(err)) + ")");
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) fail(std::string("cannot read the ") + what + " (" + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) fail("not a regular file");
  if (st.st_size > static_cast<off_t>(max_bytes)) fail(too_large);
  std::string text;
  char buffer[8192];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(std::string("cannot read the ") + what + " (" + std::strerror(errno) + ")");
    }
    if (n == 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) fail(too_large);
  }
  return text;
}

}  // namespace kccd::calib::detail
