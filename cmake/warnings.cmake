# Every target of ours builds with the same strict warnings, as errors.
add_library(symb_warnings INTERFACE)
target_compile_options(symb_warnings INTERFACE -Wall -Wextra -Werror -Wshadow -Wnon-virtual-dtor)
