#!/usr/bin/env bash
# Builds every libFuzzer target (Clang) and runs each for SECONDS on WORK/NAME/corpus: a copy of
# its seed corpus, seeds written by the project's own writers where it has a kind of them
# (fuzz_seeds: model files of every version, HDF5 fixtures), plus what earlier runs into the
# same WORK found (libFuzzer adds to the folder it is given, never to fuzz/corpus), with its
# dictionary where there is one. First every input kept in fuzz/regressions/NAME/ (the findings
# of earlier campaigns) is replayed once. Prints one summary line per target (executions,
# coverage, features, corpus size) and exits non-zero when any target finds a crash, undefined
# behaviour, a leak, a timeout or an out-of-memory input; the reproducer is left in WORK/NAME/
# (crash-*, leak-*, timeout-*, oom-*).
#   fuzz/run_all.sh SECONDS [BUILD_DIR] [WORK_DIR]
set -uo pipefail
seconds=${1:?usage: fuzz/run_all.sh SECONDS [BUILD_DIR] [WORK_DIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
build=${2:-$root/build-fuzz}
work=${3:-$build/fuzz-runs}
# FUZZ_TARGETS="fuzz_model fuzz_hdf5" runs only those.
read -r -a targets <<<"${FUZZ_TARGETS:-fuzz_amrex fuzz_particles fuzz_vtk fuzz_enzo fuzz_chombo fuzz_flash fuzz_hdf5 fuzz_native fuzz_raw fuzz_model fuzz_scene fuzz_mesh fuzz_messages}"

# A build folder already configured with the fuzz targets (a Clang sanitizer build, say) is used
# as it is; any other is configured as a Clang release build of the fuzz targets alone.
if ! grep -q '^EXABRICKS_BUILD_FUZZERS:BOOL=ON$' "$build/CMakeCache.txt" 2>/dev/null; then
  cxx=$(command -v clang++ || command -v clang++-14) || { echo "fuzz/run_all.sh needs clang++ (clang-14)" >&2; exit 1; }
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER="$cxx" -DEXABRICKS_BUILD_FUZZERS=ON \
    -DEXABRICKS_BUILD_TESTS=OFF -DEXABRICKS_PYTHON=OFF >/dev/null || exit 1
fi
nice -n 10 cmake --build "$build" -j2 --target "${targets[@]}" fuzz_seeds || exit 1

status=0
for t in "${targets[@]}"; do
  name=${t#fuzz_}
  dir=$work/$name
  mkdir -p "$dir/corpus"
  rm -f "$dir"/log.txt "$dir"/crash-* "$dir"/leak-* "$dir"/timeout-* "$dir"/oom-* "$dir"/slow-unit-*
  [ -d "$root/fuzz/corpus/$name" ] && cp "$root/fuzz/corpus/$name"/* "$dir/corpus/"
  case $name in
    model|hdf5) "$build/fuzz/fuzz_seeds" "$name" "$dir/corpus" || { echo "$t: cannot write its seeds"; status=1; } ;;
  esac
  common=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -artifact_prefix="$dir/")
  rc=0
  if [ -d "$root/fuzz/regressions/$name" ]; then
    (cd "$dir" && "$build/fuzz/$t" "${common[@]}" "$root/fuzz/regressions/$name"/* >"$dir/regressions.txt" 2>&1)
    rc=$?
    if [ "$rc" -ne 0 ]; then
      echo "$t: a kept regression input fails again (exit $rc)"
      grep -m1 -A12 -E 'ERROR: |runtime error|==ERROR' "$dir/regressions.txt" | head -20
      status=1
    fi
  fi
  args=(-max_total_time="$seconds" "${common[@]}" -max_len=65536 -print_final_stats=1)
  [ -f "$root/fuzz/$name.dict" ] && args+=(-dict="$root/fuzz/$name.dict")
  (cd "$dir" && "$build/fuzz/$t" "${args[@]}" corpus >"$dir/log.txt" 2>&1)
  rc=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$dir/log.txt" | grep -o '[0-9]*$')
  cov=$(grep -oE '(#[0-9]+|DONE).*cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' "$dir/log.txt" | tail -1 |
        grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+')
  findings=$(ls "$dir" | grep -E '^(crash|leak|timeout|oom|slow-unit)-' | tr '\n' ' ')
  echo "$t: ${runs:-?} executions, ${cov:-no coverage line}, exit $rc${findings:+, findings: $findings}"
  if [ "$rc" -ne 0 ] || [ -n "$findings" ]; then
    status=1
    grep -m1 -A12 -E 'ERROR: |runtime error|==ERROR' "$dir/log.txt" | head -20
  fi
done
exit $status
