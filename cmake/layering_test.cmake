# Registers the `layering` CTest test: fails when a file includes a layer below its own
# (ARCHITECTURE.md's table; see cmake/check_layering.cmake). include() this after enable_testing().
add_test(NAME layering
  COMMAND ${CMAKE_COMMAND} "-DSOURCE_DIR=${PROJECT_SOURCE_DIR}" -P "${PROJECT_SOURCE_DIR}/cmake/check_layering.cmake")
set_tests_properties(layering PROPERTIES LABELS "lint" TIMEOUT 60)
