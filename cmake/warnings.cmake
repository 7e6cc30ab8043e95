# Every target of ours builds with the same strict warnings, as errors.
add_library(symb_warnings INTERFACE)
target_compile_options(symb_warnings INTERFACE -Wall -Wextra -Werror -Wshadow -Wnon-virtual-dtor)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  # g++ 12 at -O3 reports a false -Wrestrict inside std::string's operator+ (GCC bug 105329).
  target_compile_options(symb_warnings INTERFACE -Wno-restrict)
endif()
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND SYMB_SANITIZE)
  # Sanitizer instrumentation makes g++ see "maybe uninitialized" values inside the standard
  # library (std::function in <regex>); GCC's manual warns of such false positives. The normal
  # build keeps the warning.
  target_compile_options(symb_warnings INTERFACE -Wno-maybe-uninitialized)
endif()
