#!/usr/bin/env bash
# bench:gpu on a lent GPU machine (the device tool), from the bundle that
# `npm run bench:gpu -- --pack` made in .gpu-bundle/ (carried with the call):
# the Vulkan loader unpacked into /, Node and Dawn's binding decompressed, the
# converter's Python packages installed from wheels, then the benchmark,
# writing its results into $OUT (or the folder given as the first argument).
# Further arguments go to the benchmark (e.g. --max-seconds 300).
set -u
cd "$(dirname "$0")/../.."
B=.gpu-bundle
OUTDIR="${1:-${OUT:-benchmarks/results}}"
shift || true
[ -f "$B/bench-gpu.mjs" ] || { echo "no $B/bench-gpu.mjs: run npm run bench:gpu -- --pack first, and carry .gpu-bundle"; exit 2; }
mkdir -p "$OUTDIR"
# the Vulkan loader (and GL dispatch libraries), as the device README says
if ! ldconfig -p | grep -q 'libvulkan.so.1 '; then
  for f in "$B"/gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES="$icd" VK_ICD_FILENAMES="$icd"
unxz() { if command -v xz >/dev/null; then xz -dc "$1"; else python3 -c 'import lzma,sys,shutil; shutil.copyfileobj(lzma.open(sys.argv[1]), sys.stdout.buffer)' "$1"; fi; }
mkdir -p /tmp/bench-gpu
unxz "$B/node.xz" >/tmp/bench-gpu/node && chmod +x /tmp/bench-gpu/node
dawn="$B/node_modules/webgpu/dist/linux-x64/dawn.node"
[ -f "$dawn" ] || unxz "$dawn.xz" >"$dawn"
python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade --target /tmp/bench-gpu/site "$B"/wheels/*.whl \
  && export PYTHONPATH=/tmp/bench-gpu/site
echo "node $(/tmp/bench-gpu/node --version); $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null)"
exec /tmp/bench-gpu/node "$B/bench-gpu.mjs" --out "$OUTDIR" --data "$B/data" --work /tmp/bench-gpu/work --python python3 "$@"
