# Checks the directory order of docs/architecture.md: every
# `#include "weft/<dir>/..."` in src/weft/<stage>/ (tests included) must name a
# directory that <stage> may depend on. Run as
#   cmake -DWEFT_SOURCE_DIR=<tree root> -P cmake/check_include_arrows.cmake
# Fails (FATAL_ERROR) listing every forbidden include with its file.

# What each stage may include besides itself (docs/architecture.md, "Arrows").
set(allowed_core "")
set(allowed_fiber core)
set(allowed_ply core)
set(allowed_gather core fiber ply)
set(allowed_yarn core fiber ply)
set(allowed_fit core fiber ply gather yarn)
set(allowed_render core fiber ply yarn)
set(allowed_eval core fiber ply yarn render)
set(allowed_view core fiber ply yarn render eval)
set(stages core fiber ply gather yarn fit render eval view)

if(NOT WEFT_SOURCE_DIR)
    message(FATAL_ERROR "check_include_arrows: set -DWEFT_SOURCE_DIR=<tree root>")
endif()

set(violations "")
set(checked 0)
foreach(stage IN LISTS stages)
    file(GLOB files ${WEFT_SOURCE_DIR}/src/weft/${stage}/*.h ${WEFT_SOURCE_DIR}/src/weft/${stage}/*.cpp)
    foreach(file IN LISTS files)
        math(EXPR checked "${checked} + 1")
        # Only the include lines: whole files would not survive CMake's list
        # splitting (a '[' in a comment glues the following lines together).
        file(STRINGS ${file} lines REGEX "^[ \t]*#[ \t]*include")
        foreach(line IN LISTS lines)
            if(line MATCHES "^[ \t]*#[ \t]*include[ \t]*[\"<]weft/([a-z_]+)/")
                set(target ${CMAKE_MATCH_1})
                if(NOT target STREQUAL stage)
                    list(FIND allowed_${stage} ${target} found)
                    if(found EQUAL -1)
                        file(RELATIVE_PATH rel ${WEFT_SOURCE_DIR} ${file})
                        list(APPEND violations "${rel}: ${stage} -> ${target} (${line})")
                    endif()
                endif()
            endif()
        endforeach()
    endforeach()
endforeach()

if(checked EQUAL 0)
    message(FATAL_ERROR "check_include_arrows: no source files under ${WEFT_SOURCE_DIR}/src/weft")
endif()
if(violations)
    list(JOIN violations "\n  " text)
    message(FATAL_ERROR "include arrows the architecture does not allow (docs/architecture.md):\n  ${text}")
endif()
message(STATUS "include arrows: ${checked} files, every include allowed")
