#!/bin/sh
# Doxygen's INPUT_FILTER (docs/Doxyfile): whole-line `//` comments become `///` doc comments, and a
# header's opening comment its file's description.
exec sed -e '1s|^// |/// \\file\n/// |' -e 's|^\( *\)// |\1/// |' -e 's|^\( *\)//$|\1///|' "$1"
