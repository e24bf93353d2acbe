#!/usr/bin/env bash
# Packs what bench/gpu_checks.sh needs for a GPU machine that lacks this project's build
# dependencies: the binaries of a build, the shared libraries they load (except the C library's),
# the dataset as a model file, the shared samples that the noise-target benchmarks draw (as model
# files at their paths under data/, with the fields they draw), those benchmarks, and run.sh,
# which unpacks them and runs the checks.
#
#   bench/gpu_package.sh DEST [BUILD] [DATASET] [SHARED_DATA]
set -euo pipefail
dest=${1:?usage: gpu_package.sh DEST [BUILD] [DATASET]}
build=${2:-build}
data=${3:-../shared/data/amrex/advection_3d/plt_drop}
shared=${4:-${EXABRICKS_DATA:-../shared/data}}
rm -rf "$dest"
mkdir -p "$dest/stage/bin" "$dest/stage/lib"
cp "$build/exabricks" "$build/tests/exabricks_gpu_tests" "$dest/stage/bin/"
strip "$dest/stage/bin/"*
for b in "$dest/stage/bin/"*; do
  ldd "$b" | awk '/=> \// {print $3}'
done | sort -u | grep -vE '/(libc|libm|libdl|librt|libpthread|ld-linux[^/]*)\.so' | xargs -I{} cp -L {} "$dest/stage/lib/"
"$build/exabricks" build "$data" -o "$dest/stage/dataset.exa"
for sample in amrex/advection_3d/plt_drop amrex/pelelm_3lev_3d/example_plt_3d:temp amrex/pele_eb_3d/plt_eb_3d; do
  rel=${sample%%:*}
  fields=()
  [ "$rel" != "$sample" ] && fields=(--field "${sample#*:}")
  [ -e "$shared/$rel" ] || { echo "gpu_package.sh: $shared/$rel is absent; its benchmarks will be skipped" >&2; continue; }
  mkdir -p "$dest/stage/data/$(dirname "$rel")"
  "$build/exabricks" -q build "$shared/$rel" "${fields[@]}" -o "$dest/stage/data/$rel"
done
cp bench/gpu_checks.sh bench/noise_target.py bench/majorants.py bench/pathtrace_bench.py "$dest/stage/"
tar -C "$dest/stage" -cf - . | xz -T0 -6 >"$dest/gpu.tar.xz"
rm -rf "$dest/stage"
cat >"$dest/run.sh" <<'RUN'
#!/usr/bin/env bash
# Unpacks the binaries, libraries and dataset beside this script and runs the GPU checks into $1.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
work=/tmp/exabricks-gpu
rm -rf "$work" && mkdir -p "$work" && tar -C "$work" -xJf "$here/gpu.tar.xz"
export LD_LIBRARY_PATH="$work/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
bash "$work/gpu_checks.sh" "$1" "$work/bin" "$work/dataset.exa" "$work/data"
RUN
chmod +x "$dest/run.sh"
du -sh "$dest"/*
