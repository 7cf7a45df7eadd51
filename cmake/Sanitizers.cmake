# Sanitizer builds (scripts/test --sanitize address|thread) and the libFuzzer harnesses (tests/fuzz).
# Every target of the tree is instrumented, so a report can come from any of our code; the Debian
# libraries we link are not (their own bugs are out of reach, and TSan may miss a happens-before that
# only they see: cmake/tsan.supp names those). nvcc cannot build with sanitizers: ENDORECON_CUDA=OFF.
set(ENDORECON_SANITIZE "" CACHE STRING "Instrument the build: address (ASan + UBSan) or thread (TSan)")
set_property(CACHE ENDORECON_SANITIZE PROPERTY STRINGS "" address thread)
option(ENDORECON_FUZZ "Build the libFuzzer harnesses in tests/fuzz (clang; implies ENDORECON_SANITIZE=address)" OFF)

if(ENDORECON_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "ENDORECON_FUZZ=ON needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++ "
                        "-DCMAKE_C_COMPILER=clang, e.g. scripts/test --sanitize address")
  endif()
  if(ENDORECON_SANITIZE STREQUAL "thread")
    message(FATAL_ERROR "ENDORECON_FUZZ=ON runs the harnesses under ASan + UBSan, not TSan")
  endif()
  set(ENDORECON_SANITIZE address CACHE STRING "" FORCE)
endif()

if(ENDORECON_SANITIZE)
  if(NOT ENDORECON_CUDA STREQUAL "OFF")
    message(FATAL_ERROR "ENDORECON_SANITIZE=${ENDORECON_SANITIZE} needs -DENDORECON_CUDA=OFF (nvcc builds no sanitized code)")
  endif()
  if(ENDORECON_SANITIZE STREQUAL "address")
    # UBSan stops at its first report, so a test or a harness fails instead of printing and going on.
    set(_sanitize -fsanitize=address,undefined -fno-sanitize-recover=all)
  elseif(ENDORECON_SANITIZE STREQUAL "thread")
    set(_sanitize -fsanitize=thread)
  else()
    message(FATAL_ERROR "ENDORECON_SANITIZE must be address or thread, got '${ENDORECON_SANITIZE}'")
  endif()
  # Line tables only: reports name file and line without the build time of full debug information.
  add_compile_options(${_sanitize} -fno-omit-frame-pointer
                      $<IF:$<CXX_COMPILER_ID:Clang>,-gline-tables-only,-g1>)
  add_link_options(${_sanitize})
  if(ENDORECON_FUZZ)
    # Coverage feedback for libFuzzer in every library the harnesses reach; only the harnesses link
    # libFuzzer itself (-fsanitize=fuzzer, tests/fuzz/CMakeLists.txt).
    add_compile_options(-fsanitize=fuzzer-no-link)
  endif()
  message(STATUS "endorecon: sanitizer build (${ENDORECON_SANITIZE}), fuzz harnesses ${ENDORECON_FUZZ}")
endif()
