#!/usr/bin/env bash
# Replays a run in the open-source Foxglove Studio web build (npm @foxglove/studio-base
# 1.48.0) in headless Chromium with tools/foxglove-layout.json, asserts that the run's topics
# appear and the layout's panels show, and saves a screenshot.
# Usage: tools/foxglove-replay/run.sh [RUN.mcap] [SCREENSHOT.png]
#   (defaults: a fresh yoga-mat run; docs/foxglove-replay.png)
#        tools/foxglove-replay/run.sh --live [SCREENSHOT.png]
#   connects the same build to `uncoil run scenes/yoga-mat.toml --live` on 127.0.0.1, paced at
#   0.05 (about 50 s), and asserts that messages arrive while it runs (default screenshot:
#   docs/foxglove-live.png).
# Needs node and npm, and Debian's chromium (installed with apt-get when missing and root).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/../.."
if ! command -v chromium > /dev/null; then
  if [ "$(id -u)" = 0 ]; then
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium) > /dev/null
  else
    echo "error: chromium is not installed (apt-get install chromium)" >&2
    exit 1
  fi
fi
(cd "$here" && npm ci --silent --no-audit --no-fund --ignore-scripts)
if [ "${1:-}" = --live ]; then
  cargo build --release --locked --quiet
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  out="$(mktemp -d)"
  trap 'rm -rf "$out"' EXIT
  CHROMIUM="$(command -v chromium)" node "$here/replay.mjs" --live "$port" \
    tools/foxglove-layout.json "${2:-docs/foxglove-live.png}" -- \
    target/release/uncoil run scenes/yoga-mat.toml --no-mcap --out "$out" \
    --live "127.0.0.1:$port" --pace 0.05
  exit
fi
mcap=${1:-}
if [ -z "$mcap" ]; then
  out="$(mktemp -d)"
  trap 'rm -rf "$out"' EXIT
  cargo run --release --locked --quiet -- run scenes/yoga-mat.toml --out "$out" > /dev/null 2>&1
  mcap="$out/run.mcap"
fi
CHROMIUM="$(command -v chromium)" node "$here/replay.mjs" "$mcap" tools/foxglove-layout.json \
  "${2:-docs/foxglove-replay.png}"
