# Warnings are errors on our own code only; third-party headers come in as SYSTEM.
add_library(endorecon_warnings INTERFACE)
target_compile_options(endorecon_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Werror -Wno-missing-field-initializers>)
# GCC's maybe-uninitialized is reported where third-party code is inlined into ours, past SYSTEM:
# with -march=native on an AVX-512 machine, GCC 12 flags Eigen's vector kernels (stable_norm_kernel's
# _mm512_max_pd) in any file that takes a stable norm or a decomposition that does, and the build
# failed there (2026-12-05). It stays a warning, not an error.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(endorecon_warnings INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-Wno-error=maybe-uninitialized>)
endif()
add_library(endorecon_optimize INTERFACE)
if(ENDORECON_NATIVE)
  target_compile_options(endorecon_optimize INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-march=native>)
endif()
target_compile_options(endorecon_optimize INTERFACE $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CONFIG:Release>>:-O3>)
