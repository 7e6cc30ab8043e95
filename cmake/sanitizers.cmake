# SYMB_SANITIZE=address -> ASan + UBSan; SYMB_SANITIZE=thread -> TSan. Applied to everything we
# build (not to the Debian-built GoogleTest, which is fine for both).
if(SYMB_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined -fno-sanitize-recover=all)
elseif(SYMB_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
elseif(SYMB_SANITIZE)
  message(FATAL_ERROR "SYMB_SANITIZE must be empty, 'address' or 'thread', not '${SYMB_SANITIZE}'")
endif()
