// Whether these tests were built with a sanitizer (scripts/test --sanitize), and how much slower
// that build runs the service: lease TTLs and waits for the service scale by kSlowdown, so a test
// fails on what the service does, not on how fast an instrumented build of it is.
#pragma once

namespace endorecon::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

#if defined(__SANITIZE_THREAD__)
inline constexpr bool kThreadSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif
#else
inline constexpr bool kThreadSanitizer = false;
#endif

// Measured 2026-12-01: training under ASan + UBSan runs about 5x slower than the Release build on
// the 2-core VM, and TSan slower still.
inline constexpr int kSlowdown = kThreadSanitizer ? 8 : kAddressSanitizer ? 5 : 1;

}  // namespace endorecon::testing
