# Writes the C++ source that holds weft view's page (src/weft/view/page/) as
# string literals, so that the page is served by weft itself with nothing read
# from disk at run time (docs/view.md). Run as
#   cmake -DPAGE_DIR=<src/weft/view/page> -DOUT=<file.cpp> -P cmake/embed_page.cmake
set(files "index.html|text/html\; charset=utf-8" "view.js|text/javascript\; charset=utf-8"
          "view.css|text/css\; charset=utf-8")
set(entries "")
set(bodies "")
set(i 0)
foreach(item IN LISTS files)
    string(REPLACE "|" ";" parts "${item}")
    list(GET parts 0 name)
    list(GET parts 1 type)
    file(READ ${PAGE_DIR}/${name} text)
    string(FIND "${text}" ")WEFTPAGE\"" clash)
    if(NOT clash EQUAL -1)
        message(FATAL_ERROR "${name} holds the raw string delimiter )WEFTPAGE\"")
    endif()
    string(APPEND bodies "const char kBody${i}[] = R\"WEFTPAGE(${text})WEFTPAGE\";\n")
    string(APPEND entries "    {\"/${name}\", \"${type}\", kBody${i}},\n")
    math(EXPR i "${i} + 1")
endforeach()
file(WRITE ${OUT}.tmp "// Made by cmake/embed_page.cmake from src/weft/view/page/: do not edit.
#include \"weft/view/view_server.h\"

namespace weft::view {
namespace {
${bodies}const PageFile kFiles[] = {
${entries}};
}  // namespace

const PageFile* pageFiles(size_t* count) {
    *count = sizeof kFiles / sizeof kFiles[0];
    return kFiles;
}

}  // namespace weft::view
")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUT}.tmp)
