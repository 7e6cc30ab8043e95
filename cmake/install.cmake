# The installed package (issue 21; docs/plugins.md): `cmake --install build --prefix P` puts
#   P/lib/libsymb_*.so                   the libraries (symb_apps only for `symb` and Python)
#   P/include/symb/<layer>/*.hpp         the public headers
#   P/bin/symb                           the command
#   P/lib/cmake/Symbricator/             find_package(Symbricator): Symbricator::kernel ... ::sim
#   P/lib/pkgconfig/symbricator.pc       the same for pkg-config
#   P/lib/python3/dist-packages/         the Python module (python/CMakeLists.txt)
#
# Which headers are public: every header of the library layers (kernel, os, io, robot, shell,
# control, evo, sim), except a header that includes a third-party library the package does not
# promise its users (yaml-cpp, Enki, MuJoCo, Box2D, HDF5, civetweb: they stay implementation
# details of the .so files) and the apps layer, whose headers are the command's internals. The
# rule is applied here from the files themselves, and a public header that includes a
# non-public one is a configure error, so the installed set always compiles on its own.
include(CMakePackageConfigHelpers)

set(symb_public_layers kernel os io robot shell control evo sim)
set(symb_private_include_regex "#include <(yaml-cpp|enki|mujoco|box2d|hdf5|H5|civetweb)")

set(symb_public_headers "")
set(symb_private_headers "")
foreach(layer IN LISTS symb_public_layers)
  file(GLOB_RECURSE headers RELATIVE ${PROJECT_SOURCE_DIR}/src CONFIGURE_DEPENDS
       ${PROJECT_SOURCE_DIR}/src/symb/${layer}/*.hpp)
  foreach(header IN LISTS headers)
    file(STRINGS ${PROJECT_SOURCE_DIR}/src/${header} third_party REGEX "${symb_private_include_regex}")
    if(third_party)
      list(APPEND symb_private_headers ${header})
    else()
      list(APPEND symb_public_headers ${header})
    endif()
  endforeach()
endforeach()
foreach(header IN LISTS symb_public_headers)
  file(STRINGS ${PROJECT_SOURCE_DIR}/src/${header} includes REGEX "^#include \"symb/")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^#include \"([^\"]+)\".*" "\\1" included "${line}")
    if(NOT included IN_LIST symb_public_headers)
      message(FATAL_ERROR "${header} is public but includes ${included}, which is not (cmake/install.cmake)")
    endif()
  endforeach()
  get_filename_component(dir ${header} DIRECTORY)
  install(FILES ${PROJECT_SOURCE_DIR}/src/${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${dir})
endforeach()

# Symbricator::kernel ... Symbricator::sim, and Symbricator::dds (the DDS bus, io/dds/; its public
# header includes no DDS header, the Cyclone library is its own dependency). symb_apps is
# installed for `symb` and the Python module but not exported: its headers are not public.
set(symb_exported kernel os io robot shell control evo sim dds)
set(symb_exported_targets "")
foreach(layer IN LISTS symb_exported)
  set_target_properties(symb_${layer} PROPERTIES EXPORT_NAME ${layer})
  list(APPEND symb_exported_targets symb_${layer})
endforeach()
# Users' code that includes the headers is C++20 too: the requirement travels with the targets.
target_compile_features(symb_kernel PUBLIC cxx_std_20)
install(TARGETS ${symb_exported_targets} EXPORT SymbricatorTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS symb_apps LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS symb RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

set(symb_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/Symbricator)
install(EXPORT SymbricatorTargets NAMESPACE Symbricator:: DESTINATION ${symb_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/SymbricatorConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/SymbricatorConfig.cmake INSTALL_DESTINATION ${symb_cmake_dir})
# 0.x: a minor version may change the plugin ABI (os/plugin.hpp's kPluginAbiVersion), so only the
# same major.minor is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/SymbricatorConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/SymbricatorConfig.cmake ${PROJECT_BINARY_DIR}/SymbricatorConfigVersion.cmake
        DESTINATION ${symb_cmake_dir})

# pkg-config: the same libraries, highest layer first (the order a static link would need).
set(symb_pc_libs "")
foreach(layer sim evo control shell robot dds io os kernel)
  string(APPEND symb_pc_libs " -lsymb_${layer}")
endforeach()
# Relative to the .pc file, so a prefix moved elsewhere (cmake --install --prefix) still works.
file(RELATIVE_PATH symb_pc_to_prefix /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" symb_pc_to_prefix "${symb_pc_to_prefix}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/symbricator.pc.in ${PROJECT_BINARY_DIR}/symbricator.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/symbricator.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The example out-of-tree project built against an installed prefix (examples/my_controller), in
# release builds only (the sanitizer builds are static and install nothing). It installs, then
# compiles one small file: a few seconds.
if(NOT SYMB_SANITIZE)
  add_test(NAME install.example_plugin
           COMMAND ${PROJECT_SOURCE_DIR}/examples/my_controller/install_test.sh ${PROJECT_BINARY_DIR})
  set_tests_properties(install.example_plugin PROPERTIES TIMEOUT 120)
endif()
