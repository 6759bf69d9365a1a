// Files the kccd subcommands write: outputs renamed into place, locked in-place edits (models:
// cli_model.hpp).
#pragma once

#include <functional>
#include <string>

#include <opencv2/core.hpp>

#include "kccd/overlay/common/staged_output.hpp"

namespace kccd::cli {

/// Files are written through kccd::overlay's staged outputs (one temporary name, one rename), and
/// output paths checked by its checkOutputPath and sameFile.
using overlay::checkOutputPath;
using overlay::sameFile;
using overlay::writeFileAtomically;

/// Encodes `image` as PNG and writes it atomically (overlay::writePngAtomically), errors naming
/// "<option> <path>".
void writePngAtomically(const std::string& path, const cv::Mat& image, const std::string& option);

/// Replaces the text of the file at `path` by `edit(text)`, atomically, holding an exclusive lock
/// (flock) on the file from the read to the rename, so concurrent edits of one file apply one after
/// the other and none is lost. With `expected`, the edit is refused when the file no longer holds
/// that text. An error from `edit` (an InputError) passes through; a failed read or write is a
/// UsageError naming the file; either way the file stays as it was.
void editFile(const std::string& path, const std::function<std::string(const std::string&)>& edit,
              const std::string* expected = nullptr);

}  // namespace kccd::cli
