#!/usr/bin/env bash
# End-to-end checks of `exabricks movie` and `generate --steps`: frames equal separate renders with
# the series' global range, --frames slices, reused structures equal fresh builds, encoding.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exe=${EXABRICKS:?set EXABRICKS to the exabricks binary}
dir=${1:?usage: movie_test.sh TMPDIR}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
source "$here/cli_checks.sh"

# A series whose hierarchy changes every step, and one that keeps it for three steps.
check "generate --steps writes numbered datasets" "$exe" generate -n 30000 --steps 3 -o moving/blobs.cells
check "the series is there" bash -c "ls moving/blobs_0000.cells moving/blobs_0001.scalars moving/blobs_0002.radius.scalars >/dev/null"
check "step 0 of a series is the scene itself" bash -c "'$exe' generate -n 30000 -o still.cells && cmp still.cells moving/blobs_0000.cells && cmp still.scalars moving/blobs_0000.scalars"
check "the blobs move" bash -c "[ -s moving/blobs_0001.scalars ] && ! cmp -s moving/blobs_0000.scalars moving/blobs_0001.scalars"
check "--regrid keeps the hierarchy between regrids" bash -c "'$exe' generate -n 30000 --steps 3 --regrid 3 -o fixed/blobs.cells && cmp fixed/blobs_0000.cells fixed/blobs_0002.cells && ! cmp -s fixed/blobs_0000.scalars fixed/blobs_0002.scalars"

look=(--size 64x48 --linear --opacity 0,0,1,0.6 --frame-all --azimuth 40)
check "movie of a series into a folder" "$exe" -q movie 'moving/blobs_*.cells' -o frames "${look[@]}"
check "one frame per step" bash -c "[ \$(ls frames/frame_*.png | wc -l) -eq 3 ]"
# The global range is the union of the steps' ranges.
range=$($py - <<'EOF'
import array, glob
lo, hi = float("inf"), float("-inf")
for f in glob.glob("moving/blobs_*[0-9].scalars"):
    a = array.array("f"); a.frombytes(open(f, "rb").read())
    lo, hi = min(lo, min(a)), max(hi, max(a))
print("%.9g,%.9g" % (lo, hi))
EOF
)
check "the movie's range is the union of every step's range" $py -c "
import json; r = json.load(open('frames/scene.json'))['layers'][0]['transfer_function']['range']
lo, hi = map(float, '$range'.split(','))
assert abs(r[0] - lo) <= 1e-6 * abs(hi) and abs(r[1] - hi) <= 1e-6 * abs(hi), (r, lo, hi)"
for k in 0 1 2; do
  check "frame $k equals render of step $k with the global range" bash -c "'$exe' -q render moving/blobs_000$k.cells -o r$k.png ${look[*]} --range $range && cmp r$k.png frames/frame_0000$k.png"
  check "frame $k equals render of step $k with the movie's scene file" bash -c "'$exe' -q render moving/blobs_000$k.cells --scene frames/scene.json -o s$k.png && cmp s$k.png frames/frame_0000$k.png"
done
check "numeric order, not lexical" bash -c "mkdir -p order && for s in 2 10 1; do cp moving/blobs_0000.cells order/s_\$s.cells; cp moving/blobs_0000.scalars order/s_\$s.scalars; cp moving/blobs_0000.radius.scalars order/s_\$s.radius.scalars; done && '$exe' -q movie order -o order_frames --size 16x16 && $py -c \"
import json; i = json.load(open('order_frames/movie.json'))['inputs']; assert [p.split('/')[-1] for p in i] == ['s_1.cells', 's_2.cells', 's_10.cells'], i\""

check "explicit files keep the order given" bash -c "'$exe' -q movie order/s_10.cells order/s_2.cells order/s_1.cells -o given_frames --size 16x16 && $py -c \"
import json; i = json.load(open('given_frames/movie.json'))['inputs']; assert [p.split('/')[-1] for p in i] == ['s_10.cells', 's_2.cells', 's_1.cells'], i\""
check "a folder after a file: the folder in numeric order, a repeated step once" bash -c "'$exe' -q movie order/s_10.cells order -o mixed_frames --size 16x16 && $py -c \"
import json; i = json.load(open('mixed_frames/movie.json'))['inputs']; assert [p.split('/')[-1] for p in i] == ['s_10.cells', 's_1.cells', 's_2.cells'], i\""

check "--frames 1:2 renders exactly those frames" bash -c "'$exe' -q movie moving -o slice ${look[*]} --frames 1:2 && [ ! -e slice/frame_00000.png ] && cmp slice/frame_00001.png frames/frame_00001.png && cmp slice/frame_00002.png frames/frame_00002.png"
check "a later run renders only the missing frames" bash -c "'$exe' movie moving -o slice ${look[*]} --json 2>/dev/null | $py -c 'import json,sys; j=json.load(sys.stdin); assert j[\"rendered\"] == 1 and j[\"missing_frames\"] == 0, j' && cmp slice/frame_00000.png frames/frame_00000.png"
check "--frames past the end renders up to the last frame and says so" bash -c "'$exe' movie moving -o clamped ${look[*]} --frames 2:5 2> clamped.err && [ ! -e clamped/frame_00001.png ] && cmp clamped/frame_00002.png frames/frame_00002.png && [ ! -e clamped/frame_00003.png ] && grep -q 'the movie has 3 frames (0..2), so this renders frames 2..2' clamped.err"
fails_with "--frames starting after the movie" "outside the movie's frames 0..2" "$exe" movie moving -o bad --frames 3:5
fails_with "an input that matches nothing" "matches no dataset" "$exe" movie 'nothing_*.cells' -o bad
fails_with "an unknown movie format" "write .mp4" "$exe" movie moving -o out.avi

check "reused structures: two of three steps reuse bricks and regions" bash -c "'$exe' movie fixed -o reuse ${look[*]} --json 2>/dev/null | $py -c 'import json,sys; j=json.load(sys.stdin); assert j[\"steps_reused\"] == 2, j'"
check "reused structures give the images of fresh builds" bash -c "'$exe' -q movie fixed -o fresh ${look[*]} --no-reuse --no-prefetch && for k in 0 1 2; do cmp reuse/frame_0000\$k.png fresh/frame_0000\$k.png || exit 1; done"
same=0; for k in 1 2; do cmp -s moving/blobs_000$((k - 1)).cells moving/blobs_000$k.cells && same=$((same + 1)); done
check "a hierarchy is reused exactly when the cells are the same" bash -c "'$exe' movie moving -o again ${look[*]} --json 2>/dev/null | $py -c 'import json,sys; j=json.load(sys.stdin); assert j[\"steps_reused\"] == $same, j'"

check "orbit: N frames of one step" bash -c "'$exe' -q movie moving/blobs_0000.cells -o orbit --size 32x32 --orbit 8 && [ \$(ls orbit/frame_*.png | wc -l) -eq 8 ] && ! cmp -s orbit/frame_00000.png orbit/frame_00004.png"
check "orbit with a series: N frames, the camera circles while the steps play" bash -c "'$exe' -q movie moving -o orbit_series ${look[*]} --orbit 6 && [ \$(ls orbit_series/frame_*.png | wc -l) -eq 6 ]"
for k in 0 1 2; do
  # Frames 2k and 2k+1 show step k, from the orbit's views 2k and 2k+1.
  check "orbit with a series: frames $((2 * k)) and $((2 * k + 1)) are step $k's orbit views" bash -c "'$exe' -q movie moving/blobs_000$k.cells -o orbit_step$k ${look[*]} --range $range --orbit 6 && cmp orbit_step$k/frame_0000$((2 * k)).png orbit_series/frame_0000$((2 * k)).png && cmp orbit_step$k/frame_0000$((2 * k + 1)).png orbit_series/frame_0000$((2 * k + 1)).png"
done
check "a short series encoded as a video says how to hold its steps" bash -c "'$exe' movie moving -o hint.mp4 --size 16x16 2>&1 >/dev/null | grep -q 'each of its 3 steps for one frame: 0.13 s at 24 frames per second; --frames-per-step 24 holds'"
fails_with "orbit with fewer frames than steps" "every step needs a frame" "$exe" movie moving -o bad --orbit 2
fails_with "orbit with --frames-per-step" "leave out --frames-per-step" "$exe" movie moving -o bad --orbit 6 --frames-per-step 2

check "--annotate names each frame's own step" bash -c "'$exe' -q movie moving -o annotated ${look[*]} --annotate && for k in 0 1 2; do '$exe' -q render moving/blobs_000\$k.cells ${look[*]} --range $range --annotate -o a\$k.png && cmp a\$k.png annotated/frame_0000\$k.png || exit 1; done"
check "--annotate shows the dataset's name, not its path" bash -c "'$exe' -q render \$PWD/moving/blobs_0000.cells ${look[*]} --annotate -o abs.png && '$exe' -q render moving/blobs_0000.cells ${look[*]} --annotate -o rel.png && cmp abs.png rel.png"

cat > path.json <<'EOF'
{"camera_path": {"keyframes": [
  {"time": 0, "camera": {"position": [150, 20, 60], "look_at": [32, 32, 32], "up": [0, 0, 1]}, "opacity_scale": 0.02},
  {"time": 1, "camera": {"position": [60, 150, 80], "look_at": [32, 32, 32], "up": [0, 0, 1]}, "opacity_scale": 0.2}]}}
EOF
check "a keyframed camera path from a scene file" bash -c "'$exe' -q movie moving/blobs_0000.cells --scene path.json -o path --size 32x32 --path-frames 5 && [ \$(ls path/frame_*.png | wc -l) -eq 5 ]"
check "the path's first frame is its first keyframe" bash -c "'$exe' -q render moving/blobs_0000.cells --scene path.json --position 150,20,60 --look-at 32,32,32 --up 0,0,1 --opacity-scale 0.02 -o k0.png --size 32x32 && cmp k0.png path/frame_00000.png"

if command -v ffprobe >/dev/null && command -v ffmpeg >/dev/null; then
  check "encodes MP4 (H.264)" "$exe" -q movie moving -o out.mp4 "${look[@]}" --fps 12
  check "ffprobe: 3 frames of 64x48 at 12 fps" bash -c "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=codec_name,width,height,r_frame_rate,nb_read_frames -of csv=p=0 out.mp4 | grep -qx 'h264,64,48,12/1,3'"
  check "encodes WebM (VP9), odd sizes padded" "$exe" -q movie moving -o out.webm --size 33x21 --fps 5
  check "ffprobe: WebM frames, size and rate" bash -c "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=codec_name,width,height,r_frame_rate,nb_read_frames -of csv=p=0 out.webm | grep -qx 'vp9,34,22,5/1,3'"
else
  echo "skip encoding checks: ffmpeg is not installed"
fi
nopath=$(mktemp -d)
check "without ffmpeg: the frames and how to encode them" bash -c "PATH=$nopath '$exe' movie moving -o none.mp4 --size 16x16 2> none.err; [ \$? -eq 0 ] && [ ! -e none.mp4 ] && [ \$(ls none.mp4.frames/frame_*.png | wc -l) -eq 3 ] && grep -q 'ffmpeg is not installed' none.err && grep -q 'ffmpeg -framerate 24 -i none.mp4.frames/frame_%05d.png' none.err"
rmdir "$nopath"

if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all movie checks passed"
