#!/usr/bin/env bash
# The GPU checks in one run: the gpu-labelled tests (the CUDA back end against the CPU on every
# feature), the device study of `exabricks bench` on an AMReX plotfile and on a generated dataset
# of 100M cells (full-quality 1024x1024 frames, viewer drafts, orbit frames per second, upload
# time, GPU memory, all against the same machine's CPU cores), path tracing on both (samples per
# pixel per second, the CPU's and GPU's images to compare), renders to look at, and, where python3
# has numpy and PIL, the default path-traced frame to its noise target (bench/noise_target.py on
# both, bench/majorants.py on the GPU: with and without the majorant grid) on the shared samples
# under DATA_DIR and a generated cosmic step. Results go to OUTDIR: gpu_checks.log, the
# benchmarks' JSON, PNGs.
#
#   bench/gpu_checks.sh OUTDIR [BIN] [PLOTFILE_OR_MODEL] [DATA_DIR]
#
# BIN holds exabricks and exabricks_gpu_tests (default: build); the dataset defaults to the shared
# plt_drop plotfile, DATA_DIR to $EXABRICKS_DATA or ../shared/data. EXABRICKS_BIG_CELLS=0 skips
# the generated dataset of the device study. Where the binaries were built on another machine, bench/gpu_package.sh packs
# them with their libraries and the dataset and the packed folder's run.sh calls this script.
set -uo pipefail
out=${1:?usage: gpu_checks.sh OUTDIR [BIN] [DATASET]}
bin=${2:-build}
data=${3:-../shared/data/amrex/advection_3d/plt_drop}
data_dir=${4:-${EXABRICKS_DATA:-../shared/data}}
big_cells=${EXABRICKS_BIG_CELLS:-100000000}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
log="$out/gpu_checks.log"
say() { echo "== $*" | tee -a "$log"; }
status=0

say "machine"
{ nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv; nproc; } >>"$log" 2>&1
"$bin/exabricks" info "$data" >>"$log" 2>&1
"$bin/exabricks" info "$data" --json >"$out/info.json" 2>>"$log"

say "gpu tests"
"$bin/exabricks_gpu_tests" >>"$log" 2>&1 || status=1
grep -E '^\[  (PASSED|FAILED|SKIPPED) ' "$log"

say "path tracing: $data, 1024x1024, sun and environment, 4 bounces (16 samples per pixel; --stats frame time)"
pt=(--integrator pathtrace --sun -1,1,-1,3 --environment 0.3,0.35,0.45 --bounces 4 --size 1024x1024 --spp 16 --stats)
for d in cpu cuda; do
  "$bin/exabricks" render "$data" --device "$d" "${pt[@]}" -o "$out/pathtrace_$d.png" \
    >>"$log" 2>&1 || status=1
done
say "path tracing converges to the same image on both devices: $data, 256x256, 256 samples per pixel"
for d in cpu cuda; do
  "$bin/exabricks" render "$data" --device "$d" --integrator pathtrace --sun -1,1,-1,3 --environment 0.3,0.35,0.45 \
    --bounces 4 --size 256x256 --spp 256 --stats -o "$out/converged_$d.png" --float "$out/converged_$d.pfm" \
    >>"$log" 2>&1 || status=1
done
say "renders of $data"
for d in cpu cuda; do
  "$bin/exabricks" render "$data" --device "$d" --size 1024x1024 --stats -o "$out/plt_$d.png" >>"$log" 2>&1 || status=1
done

if [ "$big_cells" -gt 0 ]; then
say "generated dataset of $big_cells cells"
start=$SECONDS
"$bin/exabricks" generate -s blobs -n "$big_cells" -o /tmp/exabricks-big.cells >>"$log" 2>&1 || status=1
say "generated in $((SECONDS - start)) s"
"$bin/exabricks" -q build /tmp/exabricks-big.cells -o /tmp/exabricks-big.model >>"$log" 2>&1 || status=1
say "built in $((SECONDS - start)) s"
say "path tracing: generated dataset, 1024x1024 (as above)"
for d in cuda cpu; do
  "$bin/exabricks" render /tmp/exabricks-big.model --device "$d" "${pt[@]}" -o "$out/generated_pathtrace_$d.png" \
    >>"$log" 2>&1 || status=1
done
"$bin/exabricks" render /tmp/exabricks-big.model --device cuda --size 1024x1024 --stats -o "$out/generated_cuda.png" \
  >>"$log" 2>&1 || status=1

fi
say "device study: $data"
"$bin/exabricks" bench "$data" --device cpu,cuda --size 1024x1024 --frames 5 --json >"$out/bench_plotfile.json" \
  2>>"$log" || status=1
say "the viewer's refinement: a transfer-function change, drafts and 8 full passes at 1060x807"
for d in cpu cuda; do
  "$bin/exabricks" bench "$data" --device "$d" --progressive 8 --size 1060x807 --preview-divisor 1 >>"$log" 2>&1 ||
    status=1
done
if [ "$big_cells" -gt 0 ]; then
say "device study: generated dataset"
"$bin/exabricks" bench /tmp/exabricks-big.model --device cpu,cuda --size 1024x1024 --frames 3 --orbit 12 --json \
  >"$out/bench_generated.json" 2>>"$log" || status=1
fi

say "summary"
for f in "$out"/bench_*.json; do
  env -u LD_LIBRARY_PATH python3 - "$f" <<'PY' | tee -a "$log"
import json, sys
j = json.load(open(sys.argv[1]))
print(f"{j['dataset']}: {j['cells']} cells, {j['width']}x{j['height']}, {j['threads']} CPU threads")
for d in j["devices"]:
    mem = d["device_memory"].get("memory_bytes", 0) / 2**20
    print(f"  {d['in_use']:<40} full {1e3*d['full_frame_seconds']:9.2f} ms (kernel {1e3*d['full_frame_kernel_seconds']:.2f} ms)  draft {1e3*d['draft_frame_seconds']:8.2f} ms "
          f"({d['draft_frames_per_second']:.1f} fps)  orbit {d['orbit_frames_per_second']:.1f} fps  "
          f"upload {d['upload_seconds']:.3f} s  tf change {1e3*d['transfer_function_change_seconds']:.1f} ms "
          f"({d['transfer_function_change_bytes']} B)  memory {mem:.1f} MiB  x{d['full_speedup_over_first']:.1f} full, "
          f"x{d['draft_speedup_over_first']:.1f} draft, image rmse {d['image_vs_first']['rmse']:.2e}")
PY
done
if env -u LD_LIBRARY_PATH python3 -c 'import numpy, PIL' 2>/dev/null; then
  # The benchmarks run exabricks through a wrapper that keeps this environment's libraries, and
  # Python without them.
  wrapper=$(mktemp /tmp/exabricks-XXXXXX)
  printf '#!/bin/sh\nLD_LIBRARY_PATH=%q exec %q "$@"\n' "${LD_LIBRARY_PATH:-}" "$(cd "$bin" && pwd)/exabricks" >"$wrapper"
  chmod +x "$wrapper"
  for d in cuda cpu; do
    say "the default path-traced frame to its noise target, 1024x1024, on $d (bench/noise_target.py --quick)"
    env -u LD_LIBRARY_PATH PYTHONUNBUFFERED=1 python3 "$here/noise_target.py" "$wrapper" --data "$data_dir" \
      --size 1024 --quick --device "$d" --work "/tmp/noise-target-$d" 2>&1 | tee -a "$log" || status=1
  done
  say "the majorant grid on cuda (bench/majorants.py)"
  env -u LD_LIBRARY_PATH PYTHONUNBUFFERED=1 python3 "$here/majorants.py" "$wrapper" --data "$data_dir" --device cuda \
    --work /tmp/majorants-cuda 2>&1 | tee -a "$log" || status=1
  for f in /tmp/noise-target-cuda/plt_drop-d1.png /tmp/noise-target-cuda/pelelm_temp-d1.png; do
    [ -f "$f" ] && cp "$f" "$out/target_cuda_$(basename "$f")"
  done
else
  say "noise-target benchmarks skipped: python3 lacks numpy or PIL"
fi
say "exit status $status"
exit $status
