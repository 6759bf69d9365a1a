// Numbers as text: the one formatter of messages, reports and the files the suite writes.
#pragma once

#include <string>

namespace kccd {

/// `value` as printf's %g with `digits` significant digits: "0.137", "-2.5", "1e+300",
/// "1e-300", "inf", "-inf", "nan" (17 digits read back as exactly `value`).
std::string formatNumber(double value, int digits);

/// The shortest text that reads back as exactly `value`, as std::to_chars writes it: "0.1",
/// "-2.5", "1e+300", "5e-324", "inf", "-inf", "nan".
std::string shortestNumber(double value);

}  // namespace kccd
