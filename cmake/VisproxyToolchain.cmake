# Compiler settings shared by every visproxy target: warnings, sanitizers, ccache.

find_program(VISPROXY_CCACHE ccache)
if(VISPROXY_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  set(CMAKE_CXX_COMPILER_LAUNCHER "${VISPROXY_CCACHE}")
endif()

add_library(visproxy_warnings INTERFACE)
target_compile_options(visproxy_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  $<$<BOOL:${VISPROXY_WARNINGS_AS_ERRORS}>:-Werror>)

if(VISPROXY_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

# libFuzzer builds (the `fuzz` preset): every target gets coverage instrumentation, ASan
# and UBSan, so the library code a fuzz target reaches is instrumented; the fuzz targets
# themselves link with -fsanitize=fuzzer (tests/fuzz). UBSan findings abort, so that
# libFuzzer records them as crashes.
if(VISPROXY_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "VISPROXY_BUILD_FUZZERS needs clang (libFuzzer); configure with the 'fuzz' preset")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
endif()

# visproxy_target_defaults(TARGET): warnings for code we own.
function(visproxy_target_defaults target)
  target_link_libraries(${target} PRIVATE visproxy_warnings)
endfunction()
