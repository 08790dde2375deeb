#!/usr/bin/env bash
# The web viewer on an .rrd, screenshot by headless Chromium (Debian's chromium package; software
# WebGL through SwiftShader). Usage: bench/view_screenshot.sh FILE.rrd OUT.png. Skips (exit 0,
# one line) without chromium. Made docs/view.png from `a1-leg-fk view` of a 4 s PyBullet walk.
set -euo pipefail
rrd=$1 out=$2
python=${PYTHON:-.venv/bin/python}
if ! command -v chromium >/dev/null; then echo "view_screenshot: no chromium, skipped"; exit 0; fi
export RERUN_ANALYTICS=0
set -m  # the server in its own process group: `python -m rerun` runs the viewer as a child
"$python" -m rerun --web-viewer --web-viewer-port 9192 --port 9893 "$rrd" >/dev/null 2>&1 &
server=$!
trap 'kill -- -"$server" 2>/dev/null || true' EXIT
for _ in $(seq 60); do  # the web server up (at most 30 s)
  (exec 3<>/dev/tcp/127.0.0.1/9192) 2>/dev/null && break
  sleep 0.5
done
for attempt in 1 2 3; do  # a loaded machine can catch the page still loading its wasm
  rm -f "$out"
  timeout 280 chromium --headless=new --no-sandbox --ignore-gpu-blocklist --enable-webgl \
    --use-angle=swiftshader --enable-unsafe-swiftshader --disable-background-networking \
    --disable-component-update --disable-sync --no-first-run --user-data-dir="$(mktemp -d)" \
    --virtual-time-budget=180000 --run-all-compositor-stages-before-draw --screenshot="$out" \
    --window-size=1400,900 \
    "http://127.0.0.1:9192?url=rerun%2Bhttp%3A%2F%2Flocalhost%3A9893%2Fproxy" >/dev/null 2>&1 || true
  # the loading screen alone is about 10 kB; a drawn viewer over 100 kB
  if [ "$(stat -c %s "$out" 2>/dev/null || echo 0)" -gt 50000 ]; then break; fi
  echo "view_screenshot: attempt $attempt caught the viewer loading; again"
done
echo "view_screenshot: wrote $out"
