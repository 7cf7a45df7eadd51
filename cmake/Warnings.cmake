# Warnings are errors on our own code only; third-party headers come in as SYSTEM.
add_library(endorecon_warnings INTERFACE)
target_compile_options(endorecon_warnings INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Werror -Wno-missing-field-initializers>)
add_library(endorecon_optimize INTERFACE)
if(ENDORECON_NATIVE)
  target_compile_options(endorecon_optimize INTERFACE $<$<COMPILE_LANGUAGE:CXX>:-march=native>)
endif()
target_compile_options(endorecon_optimize INTERFACE $<$<AND:$<COMPILE_LANGUAGE:CXX>,$<CONFIG:Release>>:-O3>)
