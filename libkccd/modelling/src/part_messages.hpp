// Messages the part readers share.
#pragma once

#include <string>
#include <vector>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling::detail {

/// The error for a file holding several top-level parts (named in `parts`) read without
/// ReadOptions::part or ReadOptions::merge.
inline PartError severalParts(const std::string& file, const std::vector<std::string>& parts) {
  std::string list;
  for (std::size_t i = 0; i < parts.size() && i < 8; ++i) list += (i ? ", " : "") + parts[i];
  if (parts.size() > 8) list += ", ...";
  return PartError(file + ": holds " + std::to_string(parts.size()) + " top-level parts (" + list +
                   "); pick one with --part NAME, or --merge to fit them as one rigid body");
}

}  // namespace kccd::modelling::detail
