// One way to read an input file: stat first (nothing but a regular file is opened), then one
// non-blocking descriptor, read to the end within the bound.
#include "kccd/file_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string_view>

namespace kccd {
namespace {

// The system's words for an errno value.
std::string reasonOf(int system_error) {
  return system_error == ENOENT ? std::string("no such file") : std::string(std::strerror(system_error));
}

// The message of a FileError: every reader's wording.
std::string describe(const std::string& label, FileProblem kind, int system_error, std::uintmax_t max_bytes) {
  const std::string reason = reasonOf(system_error);
  switch (kind) {
    case FileProblem::Missing:
    case FileProblem::CannotOpen:
      return "cannot open the " + label + " (" + reason + ")";
    case FileProblem::Directory:
      return std::string("a folder, not ") +
             (std::string_view("aeiou").find(label.empty() ? 'x' : label[0]) == std::string_view::npos ? "a " : "an ") +
             label;
    case FileProblem::NotRegular:
      return "not a regular file (a device, FIFO or socket)";
    case FileProblem::TooLarge:
      if (max_bytes >= (std::uintmax_t{1} << 20) && max_bytes % (std::uintmax_t{1} << 20) == 0)
        return "larger than " + std::to_string(max_bytes >> 20) + " MiB";
      if (max_bytes >= 1024 && max_bytes % 1024 == 0) return "larger than " + std::to_string(max_bytes >> 10) + " KiB";
      return "larger than " + std::to_string(max_bytes) + " bytes";
    case FileProblem::CannotRead:
      return "cannot read the " + label + " (" + reason + ")";
  }
  return "cannot read the " + label;
}

}  // namespace

FileError::FileError(const std::string& path, const std::string& label, FileProblem kind, int system_error,
                     std::uintmax_t size, std::uintmax_t max_bytes)
    : InputError(InputLocation{printable(path, 1024), 0, 0, {}}, describe(label, kind, system_error, max_bytes)),
      kind_(kind),
      system_error_(system_error),
      size_(size),
      max_bytes_(max_bytes) {}

std::string FileError::systemReason() const { return reasonOf(system_error_); }

std::string readRegularFile(const std::string& path, std::uintmax_t max_bytes, const std::string& label) {
  const auto fail = [&](FileProblem kind, int system_error, std::uintmax_t size) {
    throw FileError(path, label, kind, system_error, size, max_bytes);
  };
  const auto checkType = [&](const struct stat& st) {
    if (S_ISDIR(st.st_mode)) fail(FileProblem::Directory, 0, 0);
    if (!S_ISREG(st.st_mode)) fail(FileProblem::NotRegular, 0, 0);
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(FileProblem::Missing, errno, 0);
  checkType(st);
  // Non-blocking: should the name have become a FIFO since, opening it does not wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) fail(FileProblem::CannotOpen, errno, 0);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  if (::fstat(fd, &st) != 0) fail(FileProblem::CannotRead, errno, 0);
  checkType(st);
  const auto size = static_cast<std::uintmax_t>(st.st_size);
  if (size > max_bytes) fail(FileProblem::TooLarge, 0, size);
  std::string data(static_cast<std::size_t>(size), '\0');
  std::size_t used = 0;
  for (;;) {
    if (used == data.size()) {
      if (data.size() > max_bytes) fail(FileProblem::TooLarge, 0, data.size());
      data.resize(data.size() + 65536);  // the file grew after fstat
    }
    const ssize_t got = ::read(fd, data.data() + used, data.size() - used);
    if (got < 0) {
      if (errno == EINTR) continue;
      fail(FileProblem::CannotRead, errno, 0);
    }
    if (got == 0) break;
    used += static_cast<std::size_t>(got);
  }
  data.resize(used);
  if (used > max_bytes) fail(FileProblem::TooLarge, 0, used);
  return data;
}

}  // namespace kccd
