#pragma once
// Wall-clock budgets that a test hands to the code under test — an optimizer's or planner's time
// limit, an input and not an assertion — are multiplied by kBudgetScale in the AddressSanitizer +
// UBSan build (scripts/test --sanitize), where instrumented -O1 code runs several times slower
// than Release. What the test asserts about the result (status, tolerances, limits) is the same in
// both builds. Timings the test itself asserts are not scaled with this.

namespace chasles::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr double kBudgetScale = 10.0;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr double kBudgetScale = 10.0;
#else
inline constexpr double kBudgetScale = 1.0;
#endif
#else
inline constexpr double kBudgetScale = 1.0;
#endif

/// `seconds` in Release, `seconds * kBudgetScale` under the sanitizers.
inline constexpr double Budget(double seconds) { return seconds * kBudgetScale; }

}  // namespace chasles::test
