#!/usr/bin/env bash
# Opens a shutterlab report in headless Chromium (Debian's /usr/bin/chromium; `apt-get install -y
# chromium`), fails on any script error or when the charts did not all draw, and saves a
# screenshot. The page sets body data-status="ok" once every chart is drawn and collects script
# errors and unhandled rejections in body data-errors (estimate/report/html_report.h).
#   scripts/check_report.sh REPORT.html [SCREENSHOT.png]
set -euo pipefail
report=${1:?usage: scripts/check_report.sh REPORT.html [SCREENSHOT.png]}
shot=${2:-${report%.html}.png}
browser=${CHROMIUM:-/usr/bin/chromium}
[ -f "$report" ] || { echo "check_report: $report: no such file" >&2; exit 2; }
[ -x "$browser" ] || { echo "check_report: $browser not found (apt-get install -y chromium)" >&2; exit 2; }
url="file://$(realpath "$report")"
profile=$(mktemp -d)
dom=$(mktemp)
trap 'rm -rf "$profile" "$dom"' EXIT
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run
       --disable-background-networking --disable-component-update --disable-sync
       --user-data-dir="$profile" --virtual-time-budget=5000 --hide-scrollbars)
timeout 120 "$browser" "${flags[@]}" --dump-dom "$url" >"$dom" 2>/dev/null || true
body=$(grep -o '<body[^>]*>' "$dom" | head -1 || true)
errors=$(sed -n 's/.*data-errors="\([^"]*\)".*/\1/p' <<<"$body")
if [ -n "$errors" ]; then
  echo "check_report: script errors: $errors" >&2
  exit 1
fi
if ! grep -q 'data-status="ok"' <<<"$body"; then
  echo "check_report: the page did not finish drawing (body: ${body:-none})" >&2
  exit 1
fi
charts=$(grep -c 'class="uplot' "$dom" || true)
timeout 120 "$browser" "${flags[@]}" --window-size=1400,${HEIGHT:-4000} --screenshot="$(realpath -m "$shot")" \
  "$url" >/dev/null 2>&1 || true
[ -s "$shot" ] || { echo "check_report: no screenshot written to $shot" >&2; exit 1; }
echo "check_report: ok ($charts charts drawn, no script errors); screenshot $shot"
