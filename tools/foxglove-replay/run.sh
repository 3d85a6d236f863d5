#!/usr/bin/env bash
# Replays a run in the open-source Foxglove Studio web build (npm @foxglove/studio-base
# 1.48.0) in headless Chromium with tools/foxglove-layout.json, asserts that the run's topics
# appear and the layout's panels show, and saves a screenshot.
# Usage: tools/foxglove-replay/run.sh [RUN.mcap] [SCREENSHOT.png]
#   (defaults: a fresh yoga-mat run; docs/foxglove-replay.png)
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
mcap=${1:-}
if [ -z "$mcap" ]; then
  out="$(mktemp -d)"
  trap 'rm -rf "$out"' EXIT
  cargo run --locked --quiet -- run scenes/yoga-mat.toml --out "$out" > /dev/null 2>&1
  mcap="$out/run.mcap"
fi
CHROMIUM="$(command -v chromium)" node "$here/replay.mjs" "$mcap" tools/foxglove-layout.json \
  "${2:-docs/foxglove-replay.png}"
