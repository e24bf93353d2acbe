#!/usr/bin/env bash
# `mpirun -np N exabricks render|movie`: image-parallel images equal the serial image bit for bit;
# data-parallel images equal it within the stated tolerances and each part holds exactly its box
# and halo; a failure in the processes stops all of them (no hang); commands without a parallel
# mode refuse.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exe=${EXABRICKS:?set EXABRICKS to the exabricks binary}
dir=${1:?usage: mpi_test.sh TMPDIR}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
source "$here/cli_checks.sh"
# Tests run as root in containers; Open MPI refuses that unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
# Under the sanitizers, leak checking stays with the serial tests: Open MPI keeps memory to exit.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
run() { timeout 120 mpirun --oversubscribe -np "$@"; }

"$exe" generate -n 40000 -s shells -o s.cells >/dev/null 2>&1
scene=(s.cells --size 150x110 --spp 2 --iso 0.3 --clip-plane 40,40,40,1,0.2,0 --ao 2)
check "serial render" "$exe" -q render "${scene[@]}" -o serial.png
for n in 1 2 3 4; do
  check "mpirun -np $n render equals the serial image" bash -c "$(declare -f run); run $n '$exe' -q render ${scene[*]} -o np$n.png && cmp serial.png np$n.png"
done
check "statistics add up over the processes" bash -c "[ \"\$('$exe' -q render ${scene[*]} -o a.png --json | grep '\"samples\"')\" = \"\$($(declare -f run); run 2 '$exe' -q render ${scene[*]} -o b.png --json | grep '\"samples\"')\" ]"
# Path tracing to a noise target: each process's tiles take the passes they take alone.
check "serial path tracing to the noise target (denoised)" "$exe" -q render s.cells --size 64x48 --integrator pathtrace -o pt_serial.png
check "mpirun -np 2 path tracing to the denoised noise target equals the serial image" bash -c "$(declare -f run); run 2 '$exe' -q render s.cells --size 64x48 --integrator pathtrace -o pt_np2.png && cmp pt_serial.png pt_np2.png"
check "only the first process writes" bash -c "$(declare -f run); run 3 '$exe' -q render ${scene[*]} -o only.png --json | grep -c '\"samples\"' | grep -qx 1"

"$exe" generate -n 20000 --steps 3 -o series/b.cells >/dev/null 2>&1
check "serial movie" "$exe" -q movie series -o serial_frames --size 48x40
check "mpirun -np 2 movie: the same frames" bash -c "$(declare -f run); run 2 '$exe' -q movie series -o mpi_frames --size 48x40 && for k in 0 1 2; do cmp serial_frames/frame_0000\$k.png mpi_frames/frame_0000\$k.png || exit 1; done"
if command -v ffmpeg >/dev/null; then
  check "mpirun -np 3 movie encodes once" bash -c "$(declare -f run); run 3 '$exe' -q movie series -o m.mp4 --size 48x40 && [ -s m.mp4 ]"
fi

# Data-parallel: each process holds a part of the domain and its halo; the parts' images are
# composited. A two-level dataset whose refined block and hole straddle the split planes.
"$py" "$here/write_hole_dataset.py" h.cells
hscene=(h.cells --size 160x128 --spp 2 --frame-all --range -1,2.3 --opacity 0,0,1,0.6)
# A mesh (a quad above the clip plane, where only meshes remain) crosses the split planes too.
printf 'v 10 20 56\nv 54 20 60\nv 54 44 60\nv 10 44 56\nf 1 2 3\nf 1 3 4\n' > quad.obj
hsurf=("${hscene[@]}" --iso 0.5 --clip-plane 32,32,50,0,0.3,1 --mesh quad.obj)
check "serial renders of the hole dataset" bash -c "'$exe' -q render ${hscene[*]} -o hv.png --float hv.pfm && '$exe' -q render ${hsurf[*]} -o hs.png --float hs.pfm"
check "mpirun -np 1 --distribute data equals the serial image bit for bit" bash -c "$(declare -f run); run 1 '$exe' -q render ${hsurf[*]} --distribute data -o d1.png && cmp hs.png d1.png"
for n in 2 3 4; do
  # Volume: within 4.5/255 per channel. With iso-surfaces and a clip plane: a surface may flip at
  # isolated grazing pixels (the root search steps differ where a part's face cuts a region), so
  # the bound is on the mean and on the share of channels more than 2/255 off.
  check "mpirun -np $n --distribute data: volume within 4.5/255 of serial" bash -c "$(declare -f run); run $n '$exe' -q render ${hscene[*]} --distribute data -o dv$n.png --float dv$n.pfm && '$py' '$here/mpi_checks.py' diff hv.pfm dv$n.pfm 0.01765 0.001 0.002"
  check "mpirun -np $n --distribute data: iso-surfaces, a mesh and clipping match serial" bash -c "$(declare -f run); run $n '$exe' -q render ${hsurf[*]} --distribute data -o ds$n.png --float ds$n.pfm && '$py' '$here/mpi_checks.py' diff hs.pfm ds$n.pfm -1 0.002 0.005"
done
for n in 2 3; do
  check "mpirun -np $n info --json: each part holds its box and exactly its halo" bash -c "$(declare -f run); run $n '$exe' -q info h.cells --json > info$n.json && '$py' '$here/mpi_checks.py' parts info$n.json h.cells"
done
check "the first picture's defaults are the whole data's" bash -c "$(declare -f run); '$exe' render h.cells --size 64x64 -o a.png 2>&1 | grep -v wrote > serial_notes.txt; run 2 '$exe' render h.cells --size 64x64 --distribute data -o b.png 2>&1 | grep -v wrote > data_notes.txt; diff serial_notes.txt data_notes.txt"
cp h.cells bad.cells && cp h.scalars bad.scalars
"$py" -c "import struct,sys; f=open('bad.scalars','r+b'); f.seek(-4,2); f.write(struct.pack('<f', float('nan')))"
check "a process that cannot read its part stops every process" bash -c "$(declare -f run); run 2 '$exe' render bad.cells --distribute data -o x.png > bad.txt 2>&1; rc=\$?; [ \$rc -ne 0 ] && [ \$rc -ne 124 ] && grep -q 'not finite' bad.txt && [ ! -e x.png ]"

check "a process that cannot read its data stops every process" bash -c "$(declare -f run); run 2 '$exe' render missing.cells -o x.png > out.txt 2>&1; rc=\$?; [ \$rc -ne 0 ] && [ \$rc -ne 124 ] && grep -q 'missing.cells' out.txt"
check "commands without a parallel mode refuse" bash -c "$(declare -f run); run 2 '$exe' sample s.cells < /dev/null > info.txt 2>&1; [ \$? -ne 0 ] && grep -q 'runs in one process' info.txt"

if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all MPI checks passed"
