// The web view's page (web/view/*: HTML, JavaScript, CSS), embedded in the binary at build time
// (cmake/embed_files.cmake writes web_assets.cpp from the files): an installed `symb` serves its
// page from anywhere, with no file system lookup and so no path to escape from.
#pragma once

#include <span>
#include <string_view>

namespace symb::apps::view {

struct WebAsset {
  std::string_view path;  // "/index.html", "/view.js", ...
  std::string_view mime;
  std::string_view body;
};

std::span<const WebAsset> web_assets();
// The asset at `path` ("/" is "/index.html"), or null.
const WebAsset* find_web_asset(std::string_view path);

}  // namespace symb::apps::view
