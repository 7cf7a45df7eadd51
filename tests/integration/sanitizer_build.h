// Whether these tests were built with a sanitizer (scripts/test --sanitize), and how much slower
// that build runs the service: lease TTLs and waits for the service scale by kSlowdown, so a test
// fails on what the service does, not on how fast an instrumented build of it is.
#pragma once

namespace endorecon::testing {

// GCC says __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__; clang answers __has_feature.
#if defined(__has_feature)
#define ENDORECON_HAS_FEATURE(name) __has_feature(name)
#else
#define ENDORECON_HAS_FEATURE(name) 0
#endif
#if defined(__SANITIZE_ADDRESS__) || ENDORECON_HAS_FEATURE(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#if defined(__SANITIZE_THREAD__) || ENDORECON_HAS_FEATURE(thread_sanitizer)
inline constexpr bool kThreadSanitizer = true;
#else
inline constexpr bool kThreadSanitizer = false;
#endif
#undef ENDORECON_HAS_FEATURE

// Measured 2026-12-01: training under ASan + UBSan runs about 5x slower than the Release build on
// the 2-core VM, and TSan slower still.
inline constexpr int kSlowdown = kThreadSanitizer ? 8 : kAddressSanitizer ? 5 : 1;

}  // namespace endorecon::testing
