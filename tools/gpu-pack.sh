#!/usr/bin/env bash
# Packs what a lent GPU machine needs to run the benches into gpu-pack/ (ignored by git; pass it to the device
# tool's `carry`): the stripped, xz-compressed release binary and GPU rays bench and Debian's Vulkan loader and glvnd libraries (the machine has the
# NVIDIA driver and its ICD but no loader, and no network). docs/bench/gpu-h200/README.md tells the rest.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-target}"
cargo build --release
# The GPU rays bench (benches/gpu_rays.rs): each walk's rays per second alone.
rays_bench=$(cargo bench --bench gpu_rays --no-run 2>&1 | sed -n 's/.*Executable .*(\(.*gpu_rays-[0-9a-f]*\)).*/\1/p' | tail -1)
[ -x "$rays_bench" ] || { echo "gpu-pack: no gpu_rays bench binary" >&2; exit 1; }
rm -rf gpu-pack
mkdir -p gpu-pack
strip -o gpu-pack/glowbrick "$target/release/glowbrick"
strip -o gpu-pack/gpu_rays "$rays_bench"
xz -T0 gpu-pack/glowbrick gpu-pack/gpu_rays
(
  cd gpu-pack
  # The NVIDIA ICD (libGLX_nvidia) needs glvnd's GL libraries beside the loader.
  apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null
  for deb in *.deb; do dpkg -x "$deb" vulkan; done
  rm ./*.deb
)
du -sh gpu-pack
