#!/usr/bin/env bash
# bootstrap.sh — install what is missing (Debian), build, then run one job.
#   scripts/bootstrap.sh demo   build (Release) and run the demo pipeline
#   scripts/bootstrap.sh test   build (Release) and run the whole test suite
#   scripts/bootstrap.sh build  only install and build
# Environment: BUILD_DIR (default build), JOBS (default nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-build}
build=${BUILD_DIR:-build}
jobs=${JOBS:-$(nproc)}

missing=()
while read -r pkg; do
  case "$pkg" in ''|'#'*) continue ;; esac
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done < scripts/deps.txt
if [ ${#missing[@]} -gt 0 ]; then
  echo "bootstrap: installing ${missing[*]}" >&2
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >&2
fi

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >&2
cmake --build "$build" -j "$jobs" >&2

case "$mode" in
  build) ;;
  demo) "./$build/eventlfm" demo --out "${DEMO_OUT:-demo-out}" ;;
  test)
    # The default suite leaves out tests labelled "slow" (run by bench/).
    cd "$build" && ctest --output-on-failure -j "$jobs" -LE slow ;;
  *) echo "bootstrap: unknown mode '$mode' (demo, test, build)" >&2; exit 2 ;;
esac
