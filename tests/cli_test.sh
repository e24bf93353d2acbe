#!/usr/bin/env bash
# End-to-end checks of the exabricks command line: outputs, JSON, exit codes and error messages.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exe=${EXABRICKS:?set EXABRICKS to the exabricks binary}
dir=${1:?usage: cli_test.sh TMPDIR}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
source "$here/cli_checks.sh"

check "info on the default dataset" "$exe" info
check "info --json has the required keys" bash -c "'$exe' info --json | $py -c '
import json,sys; j=json.load(sys.stdin)
for k in (\"cells\",\"bricks\",\"regions\",\"bricks_per_region_by_count\",\"bricks_per_region_by_volume\",\"levels\"): assert k in j, k
assert j[\"cells\"] == sum(l[\"cells\"] for l in j[\"levels\"])
assert all(l[\"cell_width\"] == 2 ** l[\"level\"] for l in j[\"levels\"])'"
check "generate writes a dataset" "$exe" generate -s shells -n 20000 --seed 3 -o s.cells
check "generate is deterministic" bash -c "'$exe' generate -s shells -n 20000 --seed 3 -o t.cells && cmp s.cells t.cells && cmp s.scalars t.scalars && cmp s.radius.scalars t.radius.scalars"
check "info --fields lists fields" bash -c "'$exe' info s.cells --fields | tr '\n' ' ' | grep -qx 'radius scalar '"
check "build writes a model" "$exe" build s.cells -o s.model
check "no temporary files left" bash -c "! ls | grep -q tmp"
summary() { "$exe" info "$1" --json | $py -c 'import json,sys; j=json.load(sys.stdin); print(j["cells"], j["bricks"], j["regions"], j["levels"], j["fields"])'; }
same_summary() { [ "$(summary s.cells)" = "$(summary s.model)" ]; }
check "info on model equals info on cells" same_summary
printf '10 10 10\n# comment\n\n1e9 0 0\n-5 -5 -5\n' > pts.txt
check "sample prints one line per point" bash -c "[ \$('$exe' sample s.cells --points pts.txt | wc -l) -eq 3 ]"
check "sample outside gives nan" bash -c "'$exe' sample s.cells --points pts.txt | sed -n 2p | grep -qx 'nan nan nan nan'"
check "sample from stdin equals model" bash -c "diff <('$exe' sample s.cells < pts.txt) <('$exe' sample s.model -f scalar -p pts.txt)"
check "sample of a second field" bash -c "'$exe' sample s.cells -f radius -p pts.txt | head -1 | grep -qv nan"
check "convert round trip" bash -c "'$exe' convert s.cells -o c.cells && cmp s.cells c.cells && cmp s.scalars c.scalars"
check "grids fixture" bash -c "printf '0 0 0 4 4 4 0 1 2 3 4 5 6 7 8\n' > g.grids && '$exe' info g.grids --json | grep -q '\"cells\": 64'"

check "render the default dataset" "$exe" render -o default.png --size 64x48
check "render --json has statistics" bash -c "'$exe' render s.cells -o r.png --size 48x48 --stats --json | $py -c '
import json,sys; j=json.load(sys.stdin)
for k in (\"frame_seconds\",\"samples\",\"regions_visited\",\"samples_per_second\",\"visible_regions\",\"transfer_function_update_seconds\"): assert k in j, k
assert j[\"samples\"] > 0'"
check "render a model file with a debug view and a float image" "$exe" render s.model -o d.png --float d.pfm --size 32x32 --debug level
check "scene file reproduces the image" bash -c "'$exe' render s.cells -o a.png --size 40x30 --colormap magma --azimuth 70 --spp 2 --write-scene scene.json && '$exe' render s.cells --scene scene.json -o b.png && cmp a.png b.png"
check "scene file holds the options" grep -q magma scene.json
# Publication output: 16-bit PNG and OpenEXR, read back by ffmpeg's own decoders: the EXR holds the
# float image (its alpha equals the PFM's companion, its colour the PFM's where alpha is 1) and the
# 16-bit PNG's alpha equals the EXR's within 16-bit quantisation.
if command -v ffmpeg > /dev/null; then
  check "render writes OpenEXR and 16-bit PNG that ffmpeg reads" bash -c "'$exe' -q render s.cells -o p.exr --alpha --size 40x30 && '$exe' -q render s.cells -o p16.png --bits 16 --alpha --size 40x30 && '$exe' -q render s.cells -o p8.png --alpha --size 40x30 && ffmpeg -v error -y -i p.exr -f rawvideo -pix_fmt gbrapf32le p_exr.raw && ffmpeg -v error -y -i p16.png -f rawvideo -pix_fmt rgba64le p16.raw && ffmpeg -v error -y -i p8.png -f rawvideo -pix_fmt rgba p8.raw && $py -c '
import numpy as np
g, b, r, a = np.fromfile(\"p_exr.raw\", \"<f4\").reshape(4, 30, 40)
p16 = np.fromfile(\"p16.raw\", \"<u2\").reshape(30, 40, 4) / 65535.0
p8 = np.fromfile(\"p8.raw\", \"u1\").reshape(30, 40, 4) / 255.0
assert a.max() > 0.3, a.max()
assert abs(p16[..., 3] - a).max() <= 0.51 / 65535, abs(p16[..., 3] - a).max()
assert abs(p8[..., 3] - a).max() <= 0.51 / 255, abs(p8[..., 3] - a).max()
srgb = lambda c: np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(np.maximum(c, 0), 1 / 2.4) - 0.055)
shown = a > 0.05
straight = np.clip(r[shown] / a[shown], 0, 1)
assert abs(p16[..., 0][shown] - srgb(straight)).max() < 2e-4, abs(p16[..., 0][shown] - srgb(straight)).max()
'"
  fails_with "--bits other than 8 or 16" "8 or 16" "$exe" render s.cells -o x.png --bits 12
  fails_with "--alpha with JPEG" "has no alpha channel" "$exe" render s.cells -o x.jpg --alpha
fi
printf '{"colormap": "plasma", "opacity": [[0, 0], [1, 0.5]]}' > tf.json
check "render with a transfer function file" "$exe" render s.cells -o t.png --size 32x32 --tf tf.json
fails_with "unknown colour map" "unknown colour map" "$exe" render s.cells -o x.png --colormap rainbow
fails_with "bad image size" "--size" "$exe" render s.cells -o x.png --size 10xten
fails_with "unknown scene key" "bogus" bash -c "echo '{\"bogus\": 1}' > bad.json && '$exe' render s.cells --scene bad.json -o x.png"
fails_with "degenerate camera" "degenerate camera" "$exe" render s.cells -o x.png --position 1,1,1 --look-at 1,1,1
check "failed renders leave no image" bash -c "[ ! -e x.png ]"
# Surfaces and effects: iso-surface coloured by a second field, a mesh, clipping and AO.
printf 'v -10 -10 -1\nv 60 -10 -1\nv 60 60 -1\nv -10 60 -1\nf 1 2 3 4\n' > floor.obj
check "render surfaces, mesh, clipping and AO" bash -c "'$exe' render s.cells -o surf.png --size 48x48 --iso 0.5 --iso-color-field radius --mesh floor.obj --mesh-color 0.7,0.7,0.7 --clip-plane 20,20,20,1,0,0 --clip-box -5,-5,-5,50,50,50 --ao 2 --stats --json | $py -c '
import json,sys; j=json.load(sys.stdin); assert j[\"surface_hits\"] > 0 and j[\"ao_rays\"] > 0 and j[\"iso_regions\"] > 0 and j[\"meshes\"] == 1'"
check "surfaces through a scene file" bash -c "'$exe' render s.cells -o s1.png --size 32x32 --iso 0.3,0.6 --layer radius=magma --clip-plane 1,2,3,0,0,1 --clip-plane 4,5,6,1,0,0 --write-scene surf.json && '$exe' render s.cells --scene surf.json -o s2.png && cmp s1.png s2.png"
check "iso-surfaces only" "$exe" render s.cells -o iso.png --size 32x32 --no-volume --iso 0.4
fails_with "bad clip plane" "--clip-plane" "$exe" render s.cells -o x.png --clip-plane 1,2,3,0,0,0
fails_with "bad clip box" "--clip-box" "$exe" render s.cells -o x.png --clip-box 1,1,1,0,0,0
fails_with "iso options without values" "--iso" "$exe" render s.cells -o x.png --iso-field radius
fails_with "unknown layer field" "unknown field 'nope'" "$exe" render s.cells -o x.png --layer nope
printf 'v 0 0 0\nv 1 0 0\nf 1 2 9\n' > badidx.obj
fails_with "mesh index out of range" "badidx.obj" "$exe" render s.cells -o x.png --mesh badidx.obj
check "failed surface renders leave no image" bash -c "[ ! -e x.png ]"
amrex=${EXABRICKS_DATA:-$(dirname "$0")/../../shared/data}/amrex/pele_eb_3d/plt_eb_3d
if [ -d "$amrex" ]; then
  check "render an AMReX plotfile directly" "$exe" render "$amrex" -f density -o amrex.png --size 48x48
  check "info --fields on an AMReX plotfile" bash -c "'$exe' info '$amrex' --fields | tr '\n' ' ' | grep -qx 'volFrac density '"
else
  echo "skip AMReX checks: sample data not found at $amrex (set EXABRICKS_DATA)"
fi
if [ -n "${EXABRICKS_WRITE_FIXTURE:-}" ]; then
  cells_of() { "$exe" info "$@" --json | $py -c 'import json,sys; print(json.load(sys.stdin)["cells"])'; }
  check "write a Chombo HDF5 fixture" "$EXABRICKS_WRITE_FIXTURE" chombo "$PWD/chombo.3d.hdf5"
  check "info --fields on a Chombo file" bash -c "'$exe' info chombo.3d.hdf5 --fields | tr '\n' ' ' | grep -qx 'density energy '"
  check "render a Chombo file" "$exe" render chombo.3d.hdf5 -f energy -o chombo.png --size 48x48
  check "convert a Chombo file" "$exe" -q convert chombo.3d.hdf5 -o chombo.cells
  check "the converted file keeps every cell" test "$(cells_of chombo.cells)" = "$(cells_of chombo.3d.hdf5)"
  check "the default render of a Chombo file shows its data" bash -c "'$exe' render chombo.3d.hdf5 -o chombo-default.png --size 48x48 2>err.txt && ! grep -q 'image is empty' err.txt && grep -q \"field 'density' (the default\" err.txt"
  head -c 3000 chombo.3d.hdf5 > cut.3d.hdf5
  fails_with "truncated HDF5 file" "cut.3d.hdf5" "$exe" info cut.3d.hdf5
fi
head -c 32768 /dev/zero > zero_32x32x32_uint8.raw
check "raw volume merges to 16^3 cells" bash -c "[ \"\$('$exe' info zero_32x32x32_uint8.raw --json | $py -c 'import json,sys; print(json.load(sys.stdin)[\"cells\"])')\" = 8 ]"
fails_with "raw volume without dimensions" "--raw-dims" bash -c "cp zero_32x32x32_uint8.raw anon.raw && '$exe' info anon.raw"
fails_with "unknown option" "--bogus" "$exe" info --bogus
fails_with "unknown subcommand" "unknown command 'nope'" "$exe" nope
# Usage errors: exit 2 and one "exabricks: error:" line, whatever the parser found.
one_usage_line() { out=$("$@" 2>&1 >/dev/null); rc=$?; [ $rc -eq 2 ] && [ "$(printf '%s\n' "$out" | wc -l)" -eq 1 ] &&
  printf '%s\n' "$out" | grep -q '^exabricks: error: '; }
check "an unknown option: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --bogus
check "a missing -o: exit 2, one line" one_usage_line "$exe" render s.cells
check "--threads 0: exit 2, one line" one_usage_line "$exe" --threads 0 info s.cells
check "a misspelt command: exit 2, one line" one_usage_line "$exe" rendr s.cells
check "an unknown colour map: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --colormap nope
check "an unknown iso colour map: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --iso-colormap nope
fails_with "a word among a flag's numbers is named" "--sun: 'a' is not a finite number" "$exe" render s.cells -o x.png --sun a,b,c,d
check "a word among a flag's numbers: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --sun a,b,c,d
fails_with "a word for an integer option is named" "--fps: 'abc' is not a valid number" "$exe" movie s.cells -o m --fps abc
fails_with "--iso beyond single precision" "--iso: 1e+40 is beyond single precision" "$exe" render s.cells -o x.png --iso 1e40
fails_with "--opacity-scale beyond single precision" "beyond single precision" "$exe" render s.cells -o x.png --opacity-scale 1e40
fails_with "--range beyond single precision" "--range: 1e+40 is beyond single precision" "$exe" render s.cells -o x.png --range 0,1e40
fails_with "--albedo far out of range names its range" 'pathtrace.albedo" must be in [0, 1], not 1e+40' "$exe" render s.cells -o x.png --albedo 1e40
fails_with "a scene's vector beyond single precision" '"pathtrace.sun_direction": 1e+40 is beyond single precision' bash -c "echo '{\"pathtrace\": {\"sun_direction\": [1e40, 0, 0]}}' > big.json && '$exe' render s.cells --scene big.json -o x.png"
fails_with "a scene's iso-value beyond single precision" '"iso.values": 1e+40 is beyond single precision' bash -c "echo '{\"iso\": {\"values\": [1e40]}}' > big2.json && '$exe' render s.cells --scene big2.json -o x.png"
fails_with "a misspelt command gets a suggestion" "did you mean 'render'" "$exe" rendr s.cells -o x.png
check "global flags after the command" bash -c "'$exe' info s.cells -q --threads 1 > /dev/null"
fails_with "--rate nan names the value" "not nan" "$exe" render s.cells -o x.png --rate nan
fails_with "--elevation beyond the pole" "must be in [-90, 90]" "$exe" render s.cells -o x.png --elevation 100
check "--elevation beyond the pole: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --elevation 100
fails_with "a missing output folder, before rendering" "the folder nofolder does not exist" "$exe" render s.cells -o nofolder/x.png
check "no output for a missing folder" test ! -e nofolder
# Path tracing: its flags, their checks, and a scene file that reproduces the picture.
check "a path-traced scene file reproduces the image" bash -c "'$exe' -q render s.cells -o pt1.png --size 32x24 --spp 2 --integrator pathtrace --albedo 0.6 --anisotropy 0.3 --bounces 3 --environment 0.2,0.3,0.4 --sun 1,-1,-1,2,1 --write-scene pt.json && '$exe' -q render s.cells --scene pt.json -o pt2.png && cmp pt1.png pt2.png && ! cmp -s pt1.png flags.png"
check "the path tracer's settings are scene keys" $py -c 'import json; d = json.load(open("pt.json")); assert d["integration"]["integrator"] == "pathtrace" and d["pathtrace"]["bounces"] == 3 and d["pathtrace"]["sun_direction"] == [1, -1, -1] and abs(d["pathtrace"]["sun_angle"] - 1) < 1e-6, d["pathtrace"]'
check "--albedo 2: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --integrator pathtrace --albedo 2
fails_with "--albedo 2 names the key" 'pathtrace.albedo" must be in [0, 1], not 2' "$exe" render s.cells -o x.png --albedo 2
fails_with "--anisotropy 1 names the key" 'pathtrace.anisotropy" must be in (-1, 1), not 1' "$exe" render s.cells -o x.png --anisotropy 1
fails_with "a negative sun" 'pathtrace.sun_intensity" must be a finite number >= 0' "$exe" render s.cells -o x.png --sun 0,0,-1,-3
fails_with "a sun without intensity" "--sun expects dx,dy,dz,INTENSITY" "$exe" render s.cells -o x.png --sun 0,0,-1
fails_with "an unknown integrator" "pathtrace" "$exe" render s.cells -o x.png --integrator photon
# Path tracing is denoised and passes to a noise target by default; --spp forces a count;
# --denoise off keeps the passes' mean; a target and the denoiser need the path tracer.
check "path tracing by default: denoised, to a noise target, said once" bash -c "'$exe' render s.cells -o ptn.png --size 48x32 --integrator pathtrace --json 2>ptn.err > ptn.json && [ \$(grep -c \"until its denoised picture's noise is at most 2/255\" ptn.err) -eq 1 ] && $py -c 'import json; j = json.load(open(\"ptn.json\")); assert j[\"noise_target\"] == 2 and j[\"samples_per_pixel\"] == 1024 and 8 <= j[\"mean_samples_per_pixel\"] < 1024 and j[\"denoised\"] and j[\"denoise_seconds\"][\"guide\"] > 0, j'"
check "--spp forces the count, still denoised" bash -c "'$exe' render s.cells -o pts.png --size 48x32 --integrator pathtrace --spp 3 --json 2>/dev/null | $py -c 'import json,sys; j = json.load(sys.stdin); assert j[\"noise_target\"] == 0 and j[\"mean_samples_per_pixel\"] == 3 and j[\"denoised\"], j'"
check "--denoise off: the passes' mean" bash -c "'$exe' render s.cells -o ptu.png --size 48x32 --integrator pathtrace --spp 3 --denoise off --json 2>/dev/null | $py -c 'import json,sys; j = json.load(sys.stdin); assert not j[\"denoised\"], j' && ! cmp -s pts.png ptu.png"
check "a denoised scene file reproduces the image" bash -c "'$exe' -q render s.cells -o ptd1.png --size 48x32 --integrator pathtrace --spp 4 --write-scene ptd.json && $py -c 'import json; assert json.load(open(\"ptd.json\"))[\"frame\"][\"denoise\"] is True' && '$exe' -q render s.cells --scene ptd.json -o ptd2.png && cmp ptd1.png ptd2.png"
fails_with "the denoiser with the marcher" "the denoiser is for --integrator pathtrace" "$exe" render s.cells -o x.png --denoise on
check "the denoiser with the marcher: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --denoise on
fails_with "--denoise maybe" "must be true or false (on or off), not 'maybe'" "$exe" render s.cells -o x.png --integrator pathtrace --denoise maybe
check "--denoise maybe: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --integrator pathtrace --denoise maybe
check "--noise-target 0: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --integrator pathtrace --noise-target 0
fails_with "a negative noise target" "--noise-target: \"frame.noise_target\" must be in [0, 255], not -1" "$exe" render s.cells -o x.png --integrator pathtrace --noise-target -1
fails_with "a noise target with the marcher" "the noise target is for --integrator pathtrace" "$exe" render s.cells -o x.png --noise-target 1
check "a noise target with the marcher: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --noise-target 1
check "--spp 100000: exit 2, one line" one_usage_line "$exe" render s.cells -o x.png --spp 100000
# A scene names its input; the default dataset's scene says so, and one without an input is refused.
"$exe" -q render -o emb.png --size 24x16 --write-scene emb.json
check "the default dataset's scene names it" $py -c 'import json; assert json.load(open("emb.json"))["input"] == "<embedded>"'
check "the default dataset's scene renders again" bash -c "'$exe' -q render --scene emb.json -o emb2.png && cmp emb.png emb2.png"
$py -c 'import json; d = json.load(open("emb.json")); del d["input"]; json.dump(d, open("noinput.json", "w"))'
fails_with "a scene without an input, and none given" "noinput.json names no input" "$exe" render --scene noinput.json -o x.png
check "a scene without an input: exit 2, one line" one_usage_line "$exe" render --scene noinput.json -o x.png
check "a scene without an input renders the input given" bash -c "'$exe' -q render s.cells --scene noinput.json -o given.png"
mkdir -p empty.d stray.d && echo stray > stray.d/Header
fails_with "an empty folder says what is missing" "without a Header file" "$exe" info empty.d
fails_with "a stray Header says what is wrong" "Header is not an AMReX plotfile's" "$exe" info stray.d
mkfifo input.cells
fails_with "a FIFO as input is refused" "not a regular file or a folder" timeout 20 "$exe" info input.cells
rm -f input.cells
fails_with "missing input" "nothing.cells" "$exe" info nothing.cells
fails_with "unknown field" "unknown field 'nope'" "$exe" sample s.cells -f nope -p pts.txt
fails_with "bad point line" "line 2" bash -c "printf '1 2 3\n1 2\n' | '$exe' sample s.cells"
cp s.cells bad.cells; printf 'xx' >> bad.cells; cp s.scalars bad.scalars
fails_with "truncated cells file" "bad.cells: truncated record" "$exe" info bad.cells
head -c 1000 s.model > cut.model
fails_with "truncated model" "cut.model" "$exe" info cut.model
fails_with "build into a missing folder" "no/such" "$exe" build s.cells -o no/such/m.model
check "no half-written output" bash -c "[ ! -e no ]"
fails_with "unknown scene" "unknown scene" "$exe" generate -s nope -o x.cells

# Every point line gives one output line or a clear error; outputs that are not regular files.
check "sample: nan and out-of-range points give nan lines" bash -c "[ \"\$(printf '1 2 3\nnan 0 0\n1e400 1 1\n# note\n\n4 5 6\n' | '$exe' sample s.cells | wc -l)\" = 4 ]"
fails_with "sample: a line that is not three numbers" "line 2: expected three numbers 'x y z', got 'x y z'" bash -c "printf '1 2 3\nx y z\n' | '$exe' sample s.cells"
fails_with "sample: four numbers" "line 1" bash -c "printf '1 2 3 4\n' | '$exe' sample s.cells"
if [ -w /dev/full ]; then
  fails_with "info --json into a full disk" "writing standard output" bash -c "'$exe' info s.cells --json > /dev/full"
  fails_with "sample into a full disk" "writing standard output" bash -c "printf '1 2 3\n' | '$exe' sample s.cells > /dev/full"
  fails_with "render to a full device" "/dev/full" "$exe" render s.cells -o /dev/full --size 8x8
  check "a device is written through, never replaced" test -c /dev/full
fi
ln -sf target.png link.png
check "a symlink output replaces its target" bash -c "'$exe' render s.cells -o link.png --size 8x8 && [ -L link.png ] && [ -f target.png ]"
mkfifo pipe.png
(cat pipe.png > pipe.out) & reader=$!
check "a FIFO output is written through" bash -c "'$exe' render s.cells -o pipe.png --size 8x8 && [ -p pipe.png ]"
wait $reader
check "the FIFO carried the PNG" bash -c "head -c 8 pipe.out | od -c | grep -q 'P   N   G'"
check "JPEG output" bash -c "'$exe' render s.cells -o out.jpg --size 16x16 && head -c 3 out.jpg | od -An -tx1 | grep -q 'ff d8 ff'"
fails_with "unknown image format" "unknown image format '.gif'" "$exe" render s.cells -o x.gif
usage_rc() { "$@" > /dev/null 2>&1; [ $? -eq 2 ]; }
check "a bad option value is a usage error (exit 2)" usage_rc "$exe" render s.cells -o x.png --opacity-scale 0
fails_with "opacity scale 0 is refused" "--opacity-scale: \"transfer_function.opacity_scale\" must be a finite number > 0, not 0" "$exe" render s.cells -o x.png --opacity-scale 0
fails_with "negative opacity scale is refused" "--opacity-scale" "$exe" render s.cells -o x.png --opacity-scale -1
check "an unreadable input exits 1" bash -c "'$exe' info nothing.cells 2>/dev/null; [ \$? -eq 1 ]"
check "--version" bash -c "'$exe' --version | grep -q '^exabricks [0-9]'"
check "--threads 1 renders the same image" bash -c "'$exe' --threads 1 render s.cells -o t1.png --size 24x24 && '$exe' render s.cells -o t2.png --size 24x24 && cmp t1.png t2.png"
mkdir -p elsewhere
check "a written scene reads from another folder" bash -c "'$exe' render s.cells -o here.png --size 24x16 --mesh floor.obj --write-scene elsewhere/rel.json && cd elsewhere && '$exe' render --scene rel.json -o there.png && cmp there.png ../here.png"
# A stock ParaView preset (points over 0..1) is applied as ParaView applies it: rescaled to the data.
printf '[{"Name": "stock", "RGBPoints": [0, 0, 0, 1, 0.5, 1, 1, 1, 1, 1, 0, 0]}]' > stock.json
range=$("$exe" info s.cells --json | $py -c 'import json,sys; f=[f for f in json.load(sys.stdin)["fields"] if f["name"]=="scalar"][0]["range"]; print("%r,%r" % (f["min"], f["max"]))')
check "a preset spans the data's range" bash -c "'$exe' render s.cells -o p1.png --size 32x32 --tf stock.json --opacity 0,0,1,1 && '$exe' render s.cells -o p2.png --size 32x32 --tf stock.json --opacity 0,0,1,1 --range $range && cmp p1.png p2.png"
check "warnings for iso-values outside the data" bash -c "'$exe' render s.cells -o w.png --size 16x16 --iso 99 2>&1 >/dev/null | grep -q 'iso-value 99 lies outside'"
check "a warning for an empty image" bash -c "'$exe' render s.cells -o w.png --size 16x16 --range 50,60 2>&1 >/dev/null | grep -q 'the image is empty'"
fails_with "nothing to draw" "--no-volume leaves nothing to draw" "$exe" render s.cells -o x.png --no-volume
check "the default field is named on stderr" bash -c "'$exe' render s.cells -o w.png --size 16x16 2>&1 >/dev/null | grep -q \"field 'scalar' (the default\""
check "a colour bar and annotations are drawn" bash -c "'$exe' render s.cells -o plain.png --size 160x120 && '$exe' render s.cells -o bar.png --size 160x120 --colorbar --annotate && ! cmp -s plain.png bar.png"
# The legends as scene keys: the same bytes as the flags that set them, with or without the input named.
"$exe" -q render s.cells -o flags.png --size 160x120 --colorbar --annotate --write-scene flags.json
"$exe" -q render s.cells -o nokeys.png --size 160x120 --write-scene nokeys.json
$py -c 'import json; d = json.load(open("nokeys.json")); d["legends"] = {"color_bar": True, "annotation": True}; json.dump(d, open("keys.json", "w"))'
check "render --scene with the legend keys equals --colorbar --annotate" bash -c "'$exe' -q render s.cells --scene keys.json -o keys.png && cmp flags.png keys.png && '$exe' -q render --scene keys.json -o keys2.png && cmp flags.png keys2.png"
check "--colorbar and --annotate are recorded as scene keys" $py -c 'import json; assert json.load(open("flags.json"))["legends"] == {"color_bar": True, "annotation": True, "level_legend": False}'
"$exe" -q render --scene keys.json -o k3.png --write-scene again.json
check "a scene file round-trips the legend keys" $py -c 'import json; assert json.load(open("again.json"))["legends"] == {"color_bar": True, "annotation": True, "level_legend": False}'
check "without legend keys the image has none" bash -c "'$exe' -q render --scene nokeys.json -o nokeys2.png && cmp nokeys.png nokeys2.png && ! cmp -s nokeys.png flags.png"
# NaN written into a .scalars file: refused by default (the record named), holes with --nan-as-holes.
"$exe" info s.cells --json > s_info.json; cp s.cells nan.cells; cp s.scalars nan.scalars; cp s.radius.scalars nan.radius.scalars
$py -c 'import numpy as np; v = np.fromfile("nan.scalars", dtype=np.float32); v[[7, 70]] = np.nan; v.tofile("nan.scalars")'
fails_with "NaN values are refused by default, naming the record" "record 7: value nan of field 'scalar' is not finite" "$exe" info nan.cells
check "--nan-as-holes counts the holes on stderr" bash -c "'$exe' info nan.cells --nan-as-holes 2>&1 >/dev/null | grep -q \"nan.cells: 2 cells with NaN or infinite values in 'scalar' treated as holes\""
check "--nan-as-holes reports the holes in info --json" bash -c "'$exe' info nan.cells --nan-as-holes --json 2>/dev/null | $py -c 'import json,sys; j=json.load(sys.stdin); assert j[\"non_finite_holes\"] == {\"fields\": {\"radius\": 0, \"scalar\": 2}, \"cells\": 2}, j[\"non_finite_holes\"]; assert j[\"cells\"] == json.load(open(\"s_info.json\"))[\"cells\"] - 2'"
check "render --nan-as-holes renders" "$exe" -q render nan.cells --nan-as-holes -o nan.png --size 48x48
check "info reports the simulation's time and cycle (null when unknown)" bash -c "'$exe' info s.cells --json | $py -c 'import json,sys; j=json.load(sys.stdin); assert j[\"simulation\"] == {\"time\": None, \"cycle\": None, \"redshift\": None}'"
# An interrupted convert leaves no temporary file and either every file of the dataset or none.
# Interrupts at several moments, so that some land while the files are renamed into place.
"$exe" -q generate -s blobs -n 3000000 -o big.cells
for delay in 0.1 0.25 0.4 0.55 0.7; do
  rm -f copy.*
  "$exe" -q convert big.cells -o copy.cells & pid=$!
  sleep $delay; kill -INT $pid 2>/dev/null; wait $pid
  check "an interrupted convert leaves no temporary file (after ${delay} s)" bash -c "! ls | grep -q tmp"
  check "an interrupted convert publishes all files or none (after ${delay} s)" bash -c "n=\$(ls copy.* 2>/dev/null | wc -l); [ \$n -eq 0 ] || [ \$n -eq 3 ]"
done

# Particles beside the cells: info lists each species with its count, attributes and bytes.
check "info --json lists no particles for a native dataset" bash -c "'$exe' info s.cells --json | $py -c 'import json,sys; assert json.load(sys.stdin)[\"particles\"] == []'"
"$exe" -q generate -s cosmic -n 20000 --particles 800 -o cosmic.cells
check "generate writes the cosmic scene's dark matter and stars beside its cells" bash -c "'$exe' info cosmic.cells --json | $py -c 'import json,sys; p = json.load(sys.stdin)[\"particles\"]; assert [(s[\"species\"], s[\"count\"]) for s in p] == [(\"dark_matter\", 800), (\"star\", 32)], p; assert p[1][\"attributes\"] == [\"mass\", \"index\", \"type\", \"creation_time\"], p'"
check "render --particles draws the generated particles" bash -c "'$exe' -q render cosmic.cells --size 48x48 -o gas.png && '$exe' -q render cosmic.cells --size 48x48 --particles star --particle-radius 3 -o stars.png && ! cmp -s gas.png stars.png"
check "--particle-radius-pixels sizes the spheres in pixels: twice the pixels, larger spheres" bash -c "'$exe' -q render cosmic.cells --size 64x64 --particles --particle-radius-pixels 1 -o px1.png --write-scene px1.json && '$exe' -q render cosmic.cells --size 64x64 --particles --particle-radius-pixels 2 -o px2.png && $py -c 'import json; assert json.load(open(\"px1.json\"))[\"particles\"][\"radius_pixels\"] == 1' && '$exe' -q render --scene px1.json -o px1again.png && cmp px1.png px1again.png && ! cmp -s px1.png px2.png"
fails_with "a scene without particles refuses --particles" "scene 'blobs' has no particles" "$exe" generate -s blobs -n 1000 --particles 10 -o nop.cells
check "a dataset written over a cosmic one leaves no particles of it" bash -c "'$exe' -q generate -s blobs -n 1000 -o cosmic.cells && [ ! -e cosmic.particles ]"
check "generate --format amrex writes a plotfile the readers take, every level in boxes" bash -c "'$exe' -q generate -s ramp -n 20000 --format amrex --precision 32 -o gplt && '$exe' info gplt --json | $py -c 'import json,sys; d = json.load(sys.stdin); assert d[\"cells\"] > 15000 and len(d[\"levels\"]) == 4, d' && '$exe' -q render gplt --size 32x32 -o gplt.png"
fails_with "generate --format amrex refuses a scene with holes, leaving nothing" "data with holes" "$exe" -q generate -s shells -n 20000 --format amrex -o holes.plt
check "a refused plotfile leaves no folder behind" bash -c "[ ! -e holes.plt ] && [ ! -e holes.plt.partial ]"
fails_with "generate --format amrex will not write over a folder that is not a plotfile" "is not an AMReX plotfile; not overwritten" bash -c "mkdir -p notplt && touch notplt/keep && '$exe' -q generate -n 20000 --format amrex -o notplt"
fails_with "generate --precision takes 32 or 64" "--precision must be 32 or 64" "$exe" generate -n 1000 --format amrex --precision 16 -o p16
fails_with "generate --format amrex writes no series" "--steps writes native datasets" "$exe" generate -n 1000 --format amrex --steps 2 -o series
enzo=${EXABRICKS_DATA:-$(dirname "$0")/../../shared/data}/particles/enzo_moving7_3d/DD0010/moving7_0010
if [ -e "$enzo" ]; then
  check "info --json lists the Enzo output's dark matter" bash -c "'$exe' info '$enzo' --json | $py -c 'import json,sys; (p,) = json.load(sys.stdin)[\"particles\"]; assert (p[\"species\"], p[\"count\"], p[\"bytes_per_particle\"]) == (\"dark_matter\", 9233, 72), p; assert \"mass\" in p[\"attributes\"]'"
  check "info names the species and its attributes" bash -c "'$exe' info '$enzo' | grep -q 'particles        dark_matter: 9233 (double; 72 bytes each when read)'"
  check "render --particles draws them" bash -c "'$exe' -q render '$enzo' --size 48x48 -o gas.png && '$exe' -q render '$enzo' --size 48x48 --particles --particle-radius 0.006 -o dm.png && ! cmp -s gas.png dm.png"
  check "movie --particles draws them in every frame" bash -c "'$exe' -q movie '$enzo' --orbit 2 --size 48x48 -o gas_frames && '$exe' -q movie '$enzo' --orbit 2 --size 48x48 --particles --particle-radius 0.006 -o dm_frames && ! cmp -s gas_frames/frame_00001.png dm_frames/frame_00001.png"
  fails_with "an attribute the particles lack is refused, naming what they have" "no particle attribute 'metallicity' (dark_matter has: index, mass" "$exe" render "$enzo" --size 16x16 --particles --particle-color-by metallicity -o bad.png
  fails_with "an input taken for a species name is said" "name the input first" "$exe" render --particles "$enzo" -o bad.png
  fails_with "a species the data lacks is refused, naming what it holds" "no particle species 'stars'" "$exe" render "$enzo" --size 16x16 --particles stars -o bad.png
else
  echo "skip particle checks: sample data not found at $enzo (set EXABRICKS_DATA)"
fi

if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all command-line checks passed"
