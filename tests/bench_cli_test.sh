#!/usr/bin/env bash
# End-to-end checks of `exabricks bench`: the JSON it prints, the orbit study's CSV and plot, and
# its errors. Small images and one frame: this checks outputs, not speed.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exe=${EXABRICKS:?set EXABRICKS to the exabricks binary}
dir=${1:?usage: bench_cli_test.sh TMPDIR}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
source "$here/cli_checks.sh"

check "generate a small dataset" "$exe" -q generate -s blobs -n 20000 --seed 2 -o b.cells
check "bench --json reports every variant and ratio" bash -c "'$exe' -q bench b.cells --size 24x24 --frames 1 --json > cases.json && $py -c '
import json; j=json.load(open(\"cases.json\"))
names=[v[\"name\"] for v in j[\"variants\"]]
assert names==[\"regions, kd, adaptive\",\"cell location\",\"fixed-step sampling\",\"hide 80%, skipping on\",\"hide 80%, skipping off\",\"embree traversal\",\"analytic shading\",\"no shading\"], names
for v in j[\"variants\"]:
    assert v[\"frame_seconds\"]>0 and v[\"rays\"]==24*24, v
r=j[\"ratios\"]
for k in (\"cells_over_regions_time\",\"fixed_over_adaptive_samples\",\"fixed_over_adaptive_time\",\"skip_off_over_on_time\",\"embree_over_kd_time\",\"base_over_analytic_shading_time\",\"base_over_no_shading_time\"): assert r[k]>0, k
assert r[\"fixed_over_adaptive_samples\"]>1
# Variants that must give the same image do (without skipping, the transparent samples join the
# batches too and group the sums otherwise: round-off).
assert r[\"skip_on_vs_off_image\"][\"max_abs\"]<1e-6 and r[\"embree_vs_kd_image\"][\"max_abs\"]==0
assert r[\"cells_vs_regions_image\"][\"rmse\"]<1e-4
assert j[\"memory\"][\"peak_rss_bytes\"]>0 and j[\"memory\"][\"model_bytes\"]>0
assert j[\"build\"][\"cell_locator_nodes\"]==2*j[\"bricks\"]-1
assert j[\"cells\"]==sum(l[\"cells\"] for l in j[\"levels\"])
assert j[\"load_average_at_start\"]>=0 and j[\"load_average_at_end\"]>=0'"
check "bench --cases picks cases" bash -c "'$exe' -q bench b.cells --size 16x16 --frames 1 --cases sampling --json | $py -c '
import json,sys; j=json.load(sys.stdin)
assert [v[\"name\"] for v in j[\"variants\"]]==[\"regions, kd, adaptive\",\"fixed-step sampling\"]
assert set(j[\"ratios\"])=={\"fixed_over_adaptive_samples\",\"fixed_over_adaptive_time\",\"adaptive_vs_fixed_image\"}'"
check "bench prints a table" bash -c "'$exe' -q bench b.cells --size 16x16 --frames 1 --cases traversal | grep -q 'embree / kd traversal'"
check "orbit writes a CSV and a plot" bash -c "'$exe' -q bench b.cells --size 16x16 --orbit 5 --csv o.csv --plot o.png --json > orbit.json && $py -c '
import json,csv; j=json.load(open(\"orbit.json\")); rows=list(csv.DictReader(open(\"o.csv\")))
assert j[\"views\"]==5 and len(rows)==5
assert all(float(r[\"frame_seconds\"])>0 and int(r[\"samples\"])>0 for r in rows)
assert j[\"samples\"][\"min\"]<=j[\"samples\"][\"max\"]
assert open(\"o.png\",\"rb\").read(8)==b\"\\x89PNG\\r\\n\\x1a\\n\"'"
check "orbit without a count takes 50 views" bash -c "'$exe' -q bench b.cells --size 8x8 --orbit --csv p.csv --plot p.png > /dev/null && [ \$(wc -l < p.csv) -eq 51 ]"
fails_with "unknown case is named" "unknown case 'speed'" "$exe" -q bench b.cells --cases speed
fails_with "bad size is named" "--size expects" "$exe" -q bench b.cells --size 0x4
fails_with "bad orbit count is named" "--orbit must be" "$exe" -q bench b.cells --orbit 0

echo "$failures failure(s)"
[ "$failures" -eq 0 ]
