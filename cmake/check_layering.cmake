# Enforces the layering rule of ARCHITECTURE.md: a layer includes only itself and the layers above
# it in this table (kernel at the top, apps at the bottom), never a layer below it.
#
#   cmake -DSOURCE_DIR=/path/to/repo -P cmake/check_layering.cmake
#
# Checks every .hpp/.cpp under src/symb/<layer>/ and tests/<layer>/ (a test counts as the layer it
# tests) for `#include "symb/<layer>/..."` (or <...>). A file directly in src/symb/, in a folder that
# is not a layer, or including "symb/<not-a-layer>/..." is reported too. Each problem is printed as
# `file:line: message`; any problem fails the script (FATAL_ERROR).
cmake_minimum_required(VERSION 3.20)

set(symb_layers kernel os io robot shell control evo sim apps)
string(REPLACE ";" ", " layers_text "${symb_layers}")

if(NOT DEFINED SOURCE_DIR)
  get_filename_component(SOURCE_DIR "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
endif()
get_filename_component(SOURCE_DIR "${SOURCE_DIR}" ABSOLUTE)
if(NOT IS_DIRECTORY "${SOURCE_DIR}/src/symb")
  message(FATAL_ERROR "check_layering: no src/symb under SOURCE_DIR='${SOURCE_DIR}'")
endif()

set(violations "")
set(n_violations 0)
set(n_files 0)
set(n_includes 0)

# check_file(<absolute path> <relative path> <layer>)
function(check_file path rel layer)
  list(FIND symb_layers "${layer}" own_rank)
  file(READ "${path}" text)
  # Split into lines without CMake's list syntax getting in the way: neutralise the characters that
  # list splitting treats specially (; \ [ ]) before turning newlines into separators.
  string(REPLACE "\\" "/" text "${text}")
  string(REPLACE ";" "," text "${text}")
  string(REPLACE "[" "(" text "${text}")
  string(REPLACE "]" ")" text "${text}")
  string(REPLACE "\r" "" text "${text}")
  string(REPLACE "\n" ";" lines "${text}")
  set(line_no 0)
  set(found "")
  set(count 0)
  foreach(line IN LISTS lines)
    math(EXPR line_no "${line_no} + 1")
    if(NOT line MATCHES "^[ \t]*#[ \t]*include")
      continue()
    endif()
    if(NOT line MATCHES "^[ \t]*#[ \t]*include[ \t]*[<\"]symb/([^/\">]*)(/[^\">]*)?[\">]")
      continue()
    endif()
    set(target "${CMAKE_MATCH_1}")
    set(header "symb/${CMAKE_MATCH_1}${CMAKE_MATCH_2}")
    math(EXPR count "${count} + 1")
    list(FIND symb_layers "${target}" target_rank)
    if(target_rank EQUAL -1)
      list(APPEND found "${rel}:${line_no}: layer '${layer}' includes '${header}', which is not in a layer (${layers_text})")
    elseif(target_rank GREATER own_rank)
      list(APPEND found "${rel}:${line_no}: layer '${layer}' includes '${header}' (a layer below it)")
    endif()
  endforeach()
  set(file_problems "${found}" PARENT_SCOPE)
  set(file_includes ${count} PARENT_SCOPE)
endfunction()

file(GLOB_RECURSE src_files LIST_DIRECTORIES false RELATIVE "${SOURCE_DIR}"
  "${SOURCE_DIR}/src/symb/*.hpp" "${SOURCE_DIR}/src/symb/*.cpp")
set(test_files "")
if(IS_DIRECTORY "${SOURCE_DIR}/tests")
  file(GLOB_RECURSE test_files LIST_DIRECTORIES false RELATIVE "${SOURCE_DIR}"
    "${SOURCE_DIR}/tests/*.hpp" "${SOURCE_DIR}/tests/*.cpp")
endif()
list(SORT src_files)
list(SORT test_files)

foreach(rel IN LISTS src_files test_files)
  # src/symb/<layer>/... or tests/<layer>/...
  if(rel MATCHES "^src/symb/([^/]+)/")
    set(layer "${CMAKE_MATCH_1}")
    list(FIND symb_layers "${layer}" rank)
    if(rank EQUAL -1)
      list(APPEND violations "${rel}:1: folder 'src/symb/${layer}' is not a layer (${layers_text})")
      math(EXPR n_violations "${n_violations} + 1")
      continue()
    endif()
  elseif(rel MATCHES "^src/symb/[^/]+$")
    list(APPEND violations "${rel}:1: file is directly in src/symb/, not in a layer folder")
    math(EXPR n_violations "${n_violations} + 1")
    continue()
  elseif(rel MATCHES "^tests/([^/]+)/")
    set(layer "${CMAKE_MATCH_1}")
    list(FIND symb_layers "${layer}" rank)
    if(rank EQUAL -1)
      continue() # shared test helpers outside a layer folder are not checked
    endif()
  else()
    continue() # tests/*.cpp at the top: not a layer's test
  endif()
  math(EXPR n_files "${n_files} + 1")
  check_file("${SOURCE_DIR}/${rel}" "${rel}" "${layer}")
  math(EXPR n_includes "${n_includes} + ${file_includes}")
  foreach(problem IN LISTS file_problems)
    list(APPEND violations "${problem}")
    math(EXPR n_violations "${n_violations} + 1")
  endforeach()
endforeach()

if(n_violations GREATER 0)
  foreach(v IN LISTS violations)
    message("${v}")
  endforeach()
  message(FATAL_ERROR "layering: ${n_violations} violation(s) of the layer order (${layers_text}) in ${SOURCE_DIR}")
endif()
message("layering: OK, ${n_files} files, ${n_includes} symb/ includes, no layer includes one below it")
