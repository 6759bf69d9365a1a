// Reading an input file whole: regular files only, bounded in size, never blocking.
#pragma once

#include <cstdint>
#include <string>

#include "kccd/input_error.hpp"

namespace kccd {

/// Why a file could not be read.
enum class FileProblem : std::uint8_t {
  Missing,     ///< the path leads to nothing (no such file, or a part of it that is not a folder)
  Directory,   ///< the path is a folder
  NotRegular,  ///< the path is a device, FIFO or socket
  CannotOpen,  ///< a regular file that cannot be opened (permissions)
  TooLarge,    ///< the file holds more bytes than the bound
  CannotRead,  ///< reading failed part way
};

/// A file that cannot be read, with why as data. Its message, "path: problem" (location: the path,
/// made printable), is every reader's wording: "cannot open the <label> (no such file)" (or the
/// system's reason), "a folder, not a <label>", "not a regular file (a device, FIFO or socket)",
/// "larger than N MiB" (or KiB) or "cannot read the <label> (reason)". A reader throws its own
/// error type from location() and problem().
class FileError : public InputError {
 public:
  /// The error of reading `path`, a `label` ("camera file"), that failed with `kind`.
  FileError(const std::string& path, const std::string& label, FileProblem kind, int system_error, std::uintmax_t size,
            std::uintmax_t max_bytes);

  /// What went wrong.
  FileProblem kind() const noexcept { return kind_; }
  /// The errno of the failed call (Missing, CannotOpen, CannotRead); 0 otherwise.
  int systemError() const noexcept { return system_error_; }
  /// TooLarge: the bytes found (at least), else 0.
  std::uintmax_t size() const noexcept { return size_; }
  /// The bound the file was read with.
  std::uintmax_t maxBytes() const noexcept { return max_bytes_; }
  /// The system's words for systemError(): "no such file" for ENOENT, else strerror's text.
  std::string systemReason() const;

 private:
  FileProblem kind_;
  int system_error_;
  std::uintmax_t size_;
  std::uintmax_t max_bytes_;
};

/// The whole content of the regular file at `path`, at most `max_bytes` bytes; `label` names the
/// file in messages ("camera file"). Folders, devices, FIFOs and sockets are refused before they
/// are opened (nothing blocks), and so is a file that grows past the bound while it is read.
/// Throws FileError.
std::string readRegularFile(const std::string& path, std::uintmax_t max_bytes, const std::string& label = "file");

}  // namespace kccd
