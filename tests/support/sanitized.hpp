// Whether the suite runs under AddressSanitizer + UndefinedBehaviorSanitizer (a KCCD_SANITIZE
// build). CI runs the same tests in a Release build first: there the statistical tests draw their
// full number of cases and check their figures; under the sanitizers they draw fewer, still every
// kind of case, since what that run looks for is a memory or UB error on any path, which the
// sanitizers report at the first case that takes it.
#pragma once

namespace kccd::testing {

#ifdef KCCD_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// `full` cases normally, `sanitized` under the sanitizers.
constexpr int casesFor(int full, int sanitized) { return kSanitized ? sanitized : full; }

}  // namespace kccd::testing
