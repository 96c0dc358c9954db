#!/usr/bin/env bash
# The frame profile on a lent GPU machine, as one call (after tools/gpu-pack.sh here):
#   tools/gpu-profile.sh OUT [SIZES] [SCENES]
# writes under OUT the frame bench (every pass, GPU ms and counters) at SIZES (default 1920x1080) with the
# default walk and GI cache (traversal=auto: the occupancy walk on a GPU), then with the plain DDA
# (traversal=dda), then with the GI cache's cached static hits
# (gi_cached_hits=on, seed 001's static/dynamic split), each in its own folder, then each walk's rays alone
# (benches/gpu_rays.rs, in gpu-rays/); SCENES picks cases by label
# (default: all six). GPU_PROFILE_RUN_TIMEOUT (seconds, default none) bounds each run, so one that
# hangs cannot take the others' device time. Commit what comes back under docs/bench/gpu-NAME/.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:?usage: tools/gpu-profile.sh OUT [SIZES] [SCENES]}"
sizes="${2:-1920x1080}"
scenes=()
[ -n "${3:-}" ] && scenes=(--scenes "$3")
pack="$PWD/gpu-pack"
[ -x "$pack/glowbrick" ] || xz -dk "$pack/glowbrick.xz"
[ -x "$pack/gpu_rays" ] || [ ! -f "$pack/gpu_rays.xz" ] || xz -dk "$pack/gpu_rays.xz"
export LD_LIBRARY_PATH="$pack/vulkan/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
# The loader does not look where the lent machine keeps the NVIDIA ICD.
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES="${VK_DRIVER_FILES:-$icd}"
export GLOWBRICK_ASSETS="$PWD/assets"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
mkdir -p "$out"
run() {
  local name="$1"
  shift
  local start=$SECONDS
  timeout "${GPU_PROFILE_RUN_TIMEOUT:-0}" "$pack/glowbrick" bench --frame --sizes "$sizes" "${scenes[@]}" "$@" --out "$out/$name" >"$out/$name.log" 2>&1 ||
    echo "gpu-profile: $name failed (see $name.log)"
  echo "gpu-profile: $name in $((SECONDS - start)) s"
}
run frame
run frame-dda --set traversal=dda
run frame-gi-cached-hits --set gi_cached_hits=on
# Each walk's rays alone (benches/gpu_rays.rs), 1280x720 camera rays and the rays from their hits, all scenes.
if [ -x "$pack/gpu_rays" ]; then
  start=$SECONDS
  timeout "${GPU_PROFILE_RUN_TIMEOUT:-0}" "$pack/gpu_rays" --size 1280x720 --repeats 9 --out "$out/gpu-rays" \
    >"$out/gpu-rays.log" 2>&1 || echo "gpu-profile: gpu-rays failed (see gpu-rays.log)"
  echo "gpu-profile: gpu-rays in $((SECONDS - start)) s"
fi
