#!/usr/bin/env bash
# End-to-end checks of --memory-budget: a step larger than the budget is read and drawn in parts
# whose picture equals the in-core render of the same scene, whose first-picture defaults are the
# whole step's, and whose peak resident memory (/usr/bin/time) stays within the budget + 15 %;
# samples, info, movie frames and bench's comparison equal the in-core ones; a budget too small
# names the smallest that works.
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
exe=${EXABRICKS:?set EXABRICKS to the exabricks binary}
dir=${1:?usage: memory_budget_test.sh TMPDIR}
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
source "$here/cli_checks.sh"

# Two float images (PFM) agree as the in-core criterion asks: mean <= 0.5/255, 99.9 % of the
# channels within 2/255.
same_image() {
  $py - "$1" "$2" <<'EOF'
import sys, numpy as np
def pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); scale = float(f.readline())
        a = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return a.reshape(h, w, 3 if kind == b"PF" else 1)
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
d = np.abs(np.clip(a, 0, 1) - np.clip(b, 0, 1)) * 255
print("    mean %.4f, max %.2f, within 2/255: %.4f %%" % (d.mean(), d.max(), 100 * (d <= 2).mean()))
sys.exit(0 if d.mean() <= 0.5 and (d <= 2).mean() >= 0.999 else 1)
EOF
}
# Two 8-bit pictures (PNG) agree as the in-core criterion asks.
same_png() {
  $py - "$1" "$2" <<'EOF'
import sys, numpy as np
from PIL import Image
a, b = (np.asarray(Image.open(p).convert("RGBA")).astype(float) for p in sys.argv[1:3])
d = np.abs(a - b)
print("    mean %.4f, max %.0f, within 2/255: %.4f %%" % (d.mean(), d.max(), 100 * (d <= 2).mean()))
sys.exit(0 if a.shape == b.shape and d.mean() <= 0.5 and (d <= 2).mean() >= 0.999 else 1)
EOF
}
# Peak resident kilobytes of a command (GNU time), which must succeed.
peak_kb() { /usr/bin/time -f %M -o peak.txt "$@" >/dev/null 2>err.txt && cat peak.txt; }
within_budget() { # kilobytes, budget in MiB; sanitizer builds hold shadow memory: not measured there
  if [ -n "${EXABRICKS_SANITIZED:-}" ]; then echo "    peak not measured under the sanitizers"; return 0; fi
  $py -c "import sys; kb, mib = int('$1'), float('$2'); print('    peak %.1f MiB of %.0f MiB' % (kb / 1024, mib)); sys.exit(0 if 0 < kb / 1024 <= 1.15 * mib else 1)"
}
# The smallest budget (MiB) a command names when given too small a one, and the budget it
# names for the whole step; `between` is a budget halfway (a few parts).
smallest() { "$@" --memory-budget 1M 2>&1 >/dev/null | sed -n 's/.*(--memory-budget \([0-9]*\)M).*/\1/p'; }
whole() { "$@" --memory-budget 1M 2>&1 >/dev/null | sed -n 's/.*(held whole: --memory-budget \([0-9]*\)M).*/\1/p'; }
between() { local a b; a=$(smallest "$@"); b=$(whole "$@"); echo $(((${a:-1000} + ${b:-1000}) / 2)); }

check "generate a cosmic step" "$exe" -q generate -s cosmic -n 400000 -o c.cells
look=(--size 256x256)
check "in-core render with its scene" "$exe" -q render c.cells -o in.png --float in.pfm --write-scene in.json "${look[@]}"
least=$(smallest "$exe" render c.cells --scene in.json -o t.png)
check "a budget too small names the smallest that works (${least}M)" test -n "$least"
half=$(between "$exe" render c.cells --scene in.json -o t.png)

# The smallest budget (many parts, each read for every pass over the step) and one halfway; the
# sanitizer builds, several times slower, take the halfway one only.
budgets="${least:-1000} $half"
[ -n "${EXABRICKS_SANITIZED:-}" ] && budgets=$half
for budget in $budgets; do
  kb=$(peak_kb "$exe" render c.cells --scene in.json -o b$budget.png --float b$budget.pfm --memory-budget ${budget}M)
  check "render under ${budget}M succeeds" test -n "$kb"
  check "render under ${budget}M keeps its budget" within_budget "${kb:-0}" $budget
  check "render under ${budget}M equals the in-core render" same_image in.pfm b$budget.pfm
done
check "render with particles under ${half}M equals the in-core render" bash -c "'$exe' -q render c.cells --scene in.json --particles -o pin.png --float pin.pfm && '$exe' -q render c.cells --scene in.json --particles -o pb.png --float pb.pfm --memory-budget ${half}M && ! cmp -s pin.png in.png"
check "  (the pictures)" same_image pin.pfm pb.pfm
check "the budget was read in parts" bash -c "'$exe' render c.cells --scene in.json -o x.png --memory-budget ${half}M --json 2>/dev/null | $py -c 'import json,sys; m = json.load(sys.stdin)[\"memory\"]; assert m[\"parts\"] > 1 and m[\"resident_parts\"] >= 1, m'"

# The first picture's defaults (range, logarithmic mapping, opacity, exposure) count every part.
check "defaults under a budget are the whole step's" bash -c "'$exe' -q render c.cells -o d.png ${look[*]} --memory-budget ${half}M --write-scene d.json && $py -c \"
import json
a, b = json.load(open('in.json')), json.load(open('d.json'))
assert a['layers'] == b['layers'], (a['layers'], b['layers'])\""

# The first view frames what the whole step shows: the parts' visible cells united, with one
# margin around them all.
check "the default camera under a budget is the in-core one" bash -c "$py -c \"
import json
a, b = json.load(open('in.json'))['camera'], json.load(open('d.json'))['camera']
for k in a:
    x, y = (a[k], b[k]) if isinstance(a[k], list) else ([a[k]], [b[k]])
    assert all(abs(float(u) - float(v)) <= 1e-5 * (1 + abs(float(u))) for u, v in zip(x, y)), (k, a[k], b[k])\""

# A movie under a budget: every frame drawn from parts equals the in-core movie's frame, with the
# step's particles (generate writes them for the cosmic scene) sized in pixels.
mv=(--orbit 2 --size 128x128 --particles --particle-radius-pixels 1.5)
check "movie in core" "$exe" -q movie c.cells -o mv_in "${mv[@]}"
mvhalf=$(between "$exe" movie c.cells -o mv_t "${mv[@]}")
check "movie under a budget" bash -c "'$exe' -q movie c.cells -o mv_b ${mv[*]} --memory-budget ${mvhalf}M --json > mv.json"
check "the movie under a budget was drawn in parts" $py -c "import json; m = json.load(open('mv.json'))['memory']; assert m['largest_parts'] > 1 and m['parts_read'] > 0, m"
for f in 00000 00001; do
  check "movie frame $f under a budget equals in core" same_png mv_in/frame_$f.png mv_b/frame_$f.png
done

# bench: the budget study, its first view compared with the whole step's.
bhalf=$(between "$exe" bench c.cells --orbit 2 --size 96x96)
check "bench under a budget compares with in core" bash -c "'$exe' bench c.cells --memory-budget ${bhalf}M --orbit 2 --size 96x96 --in-core --json 2>/dev/null | $py -c '
import json, sys
j = json.load(sys.stdin)
assert j[\"parts\"] > 1 and len(j[\"orbit\"]) == 2 and j[\"first_picture_seconds\"] > 0, j
d = j[\"in_core\"][\"difference\"]
assert d[\"mean_255\"] <= 0.5 and d[\"share_within_2_255\"] >= 0.999, d'"
fails_with "bench --in-core needs a budget" "--in-core compares with a step held under --memory-budget" "$exe" bench c.cells --in-core

# Samples: every point in the part that holds it, equal to the whole step's.
$py -c "
import random
random.seed(7)
for i in range(5000): print(*(random.uniform(-0.05, 1.05) for _ in range(3)))
print('nan 0 0')" >points.txt
few=$(between "$exe" sample c.cells -p points.txt)
check "sample under a budget equals in core" bash -c "'$exe' sample c.cells -p points.txt > s_in.txt && '$exe' sample c.cells -p points.txt --memory-budget ${few}M > s_b.txt && cmp s_in.txt s_b.txt"

# info: the whole step's cells, levels and ranges from its parts (under a budget halfway for info
# itself: its process is smaller than the other commands').
inparts=$(between "$exe" info c.cells)
check "info under a budget counts the in-core cells, levels and ranges" bash -c "'$exe' info c.cells --json > i_in.json && '$exe' info c.cells --json --memory-budget ${inparts}M > i_b.json && $py -c \"
import json
a, b = json.load(open('i_in.json')), json.load(open('i_b.json'))
assert a['cells'] == b['cells'] and b['memory']['parts'] > 1, (a['cells'], b)
assert [(l['level'], l['cells']) for l in a['levels']] == [(l['level'], l['cells']) for l in b['levels']]
assert a['fields'] == b['fields'] and a['bounds'] == b['bounds']\""

# A budget too small: exit 2 with the smallest that works, and that one works.
fails_with "a budget too small names the smallest that works" "the smallest budget that works is" "$exe" render c.cells -o t.png "${look[@]}" --memory-budget 1M
check "it exits 2" bash -c "'$exe' render c.cells -o t.png ${look[*]} --memory-budget 1M 2>/dev/null; [ \$? -eq 2 ]"
check "no half-written image after a refused budget" bash -c "rm -f u.png; '$exe' render c.cells -o u.png --memory-budget 1M 2>/dev/null; [ ! -e u.png ]"
fails_with "a budget that is no size" "--memory-budget: 'lots' is not a size" "$exe" render c.cells -o t.png --memory-budget lots
fails_with "a budget of nothing" "is not a size" "$exe" info c.cells --memory-budget 0
check "a budget the step fits in draws it whole" bash -c "'$exe' render c.cells --scene in.json -o w.png --float w.pfm --memory-budget 4G --json | $py -c 'import json,sys; j = json.load(sys.stdin); assert \"memory\" not in j, j' && cmp in.pfm w.pfm"

# A real AMReX plotfile, read box by box.
data=${EXABRICKS_DATA:-$here/../../shared/data}
drop=$data/amrex/advection_3d/plt_drop
if [ -n "${EXABRICKS_SANITIZED:-}" ]; then
  echo "skip plt_drop checks under the sanitizers (the generated step's checks cover the same code)"
elif [ -d "$drop" ]; then
  check "plt_drop in-core render" "$exe" -q render "$drop" -o p_in.png --float p_in.pfm --write-scene p.json "${look[@]}"
  tight=$(between "$exe" render "$drop" --scene p.json -o p_b.png)
  kb=$(peak_kb "$exe" render "$drop" --scene p.json -o p_b.png --float p_b.pfm --memory-budget ${tight}M)
  check "plt_drop under ${tight}M keeps its budget" within_budget "${kb:-0}" $tight
  check "plt_drop under ${tight}M equals the in-core render" same_image p_in.pfm p_b.pfm
else
  echo "skip plt_drop checks: $drop is absent (shared sample data)"
fi
if [ $failures -ne 0 ]; then echo "$failures failure(s)"; exit 1; fi
echo "all memory budget checks passed"
