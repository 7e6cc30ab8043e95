#!/usr/bin/env bash
# CTest's entry to the web view's browser test (view_browser_test.cjs): finds node, Debian's
# chromium and npm's playwright-core (scripts/setup installs all three; playwright-core into
# $SYMB_WEB_TEST_DIR, by default ~/.cache/symbricator/web-test), and skips with exit status 77
# and a message when one is missing.
#   view_browser_test.sh SYMB_BINARY SCENARIO_DIR
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
dir=${SYMB_WEB_TEST_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/symbricator/web-test}
chromium=${SYMB_CHROMIUM:-$(command -v chromium || true)}
skip() {
  echo "skipped: $1 (scripts/setup installs it)"
  exit 77
}
command -v node >/dev/null 2>&1 || skip "node is not installed"
[[ -n "$chromium" && -x "$chromium" ]] || skip "chromium is not installed"
[[ -f "$dir/node_modules/playwright-core/package.json" ]] || skip "npm's playwright-core is not in $dir"
exec node "$here/view_browser_test.cjs" "$1" "$2" "$dir" "$chromium"
