"""The in situ example (examples/insitu) under mpiexec against `exabricks render`:

    python3 check_insitu.py SIMULATION SCRIPT PLUGIN EXABRICKS_CLI WORK_DIR MPIEXEC

Runs the simulation on 2 and 3 processes for 5 steps, regridding every 2, with the Catalyst script
writing an image per step and the data of steps 0 and 3. The image of step 3 equals `exabricks
render` of the data written at step 3 (same camera and transfer function) within the bounds of
check_paraview_parallel.py; the hierarchy changes between steps 0 and 3 and so do the images. A
script that fails (the plugin missing) is reported on every step and the simulation still ends
normally. Without a display (no DISPLAY, as on a compute node) the simulation runs to its end, the
script says once why ParaView's view cannot draw, and draws each step with exabricks render
instead: the same picture as the representation's within the same bounds."""
import json
import os
import re
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import ALPHA, ANGLE, COLORS, HEIGHT, UP, WIDTH, exabricks_render, read_png  # noqa: E402

simulation, script, plugin, cli, work, mpiexec = sys.argv[1:7]
os.makedirs(work, exist_ok=True)
POSITION, FOCUS, RANGE = (1.75, -0.85, 1.3), (0.5, 0.5, 0.5), (0.0, 1.0)
view = {"size": [WIDTH, HEIGHT], "position": POSITION, "focus": FOCUS, "up": UP, "angle": ANGLE, "range": RANGE,
        "colors": COLORS, "alpha": ALPHA, "unit": 1.0 / 256, "samples": 8, "every": 3}
view_path = os.path.join(work, "view.json")
with open(view_path, "w") as f:
    json.dump(view, f)


def simulate(n, out, env_plugin, display=True):
    env = dict(os.environ, EXABRICKS_INSITU_VIEW=view_path)
    if not display:
        env.pop("DISPLAY", None)
        env["EXABRICKS_CLI"] = cli
    if env_plugin:
        env["EXABRICKS_PV_PLUGIN"] = plugin
    else:
        env.pop("EXABRICKS_PV_PLUGIN", None)
    command = [mpiexec, "--oversubscribe", "-np", str(n)] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    command += ["-x", "EXABRICKS_INSITU_VIEW"] + (["-x", "EXABRICKS_PV_PLUGIN"] if env_plugin else [])
    command += [] if display else ["-x", "EXABRICKS_CLI"]
    command += [simulation, script, "--steps", "5", "--regrid", "2", "--out", out]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, env=env)


failures = []
for n in (2, 3):
    out = os.path.join(work, "np%d" % n)
    run = simulate(n, out, True)
    steps = [line for line in run.stdout.splitlines() if line.startswith("step ")]
    print("\n".join("  %d processes: %s" % (n, s) for s in steps))
    if run.returncode != 0 or len(steps) != 5 or any("failed" in s for s in steps):
        print(run.stdout[-2000:], run.stderr[-3000:])
        failures.append("%d processes: the simulation or its Catalyst script failed (exit %d)" % (n, run.returncode))
        continue
    blocks = [int(re.search(r"(\d+) blocks", s).group(1)) for s in steps]
    insitu = [read_png(os.path.join(out, "step_%04d.png" % k)) for k in (0, 3)]
    reference = exabricks_render(cli, os.path.join(out, "step_0003.vthb"), work, "step3-np%d.pfm" % n, "--spp", "8",
                                 field="density", value_range=RANGE, camera=(POSITION, FOCUS))
    d = np.abs(insitu[1] - reference).max(axis=-1)
    shown = (reference.max(axis=-1) > 0.02).mean()
    beyond, far = (d > 1.5 / 255 + 1e-9).mean(), (d > 4.5 / 255 + 1e-9).mean()
    moved = np.abs(insitu[0] - insitu[1]).mean()
    print("%d processes: step 3 in situ against exabricks render of its data: max %.1f/255, mean %.3f/255, %.2f%% "
          "beyond 1.5/255, %.3f%% beyond 4.5/255 (%.0f%% showing data); blocks %s; step 0 to 3 changes the "
          "picture by %.4f on average" % (n, 255 * d.max(), 255 * d.mean(), 100 * beyond, 100 * far, 100 * shown,
                                          blocks, moved))
    if shown < 0.02:
        failures.append("%d processes: the reference shows almost nothing" % n)
    if d.mean() > 0.5 / 255 or beyond > 0.08 or far > 0.001:
        failures.append("%d processes: the in situ image of step 3 differs from exabricks render of its data" % n)
    if blocks[0] == blocks[3] or moved < 1e-3:
        failures.append("%d processes: the hierarchy (%s blocks) or the picture did not change" % (n, blocks))

# Without a display: every step, said once, drawn by exabricks render from the data.
out = os.path.join(work, "nodisplay")
run = simulate(2, out, True, display=False)
steps = [line for line in run.stdout.splitlines() if line.startswith("step ")]
said = run.stdout.count("cannot draw")
print("without a display: exit %d, %d steps, %d reporting a failure, said %d times why the view cannot draw" %
      (run.returncode, len(steps), sum("failed" in s for s in steps), said))
if run.returncode != 0 or len(steps) != 5 or any("failed" in s for s in steps) or said != 1:
    print(run.stdout[-2000:], run.stderr[-3000:])
    failures.append("without a display the simulation or its script failed (exit %d, %d steps, said %d times)" %
                    (run.returncode, len(steps), said))
elif not os.path.exists(os.path.join(out, "step_0003.vthb")) or os.path.exists(os.path.join(out, "step_0001.vthb")):
    failures.append("without a display the data of step 3 (and only every third step) should be written")
else:
    drawn = read_png(os.path.join(out, "step_0003.png"))
    reference = exabricks_render(cli, os.path.join(out, "step_0003.vthb"), work, "step3-nodisplay.pfm", "--spp", "8",
                                 field="density", value_range=RANGE, camera=(POSITION, FOCUS))
    d = np.abs(drawn - reference).max(axis=-1)
    print("without a display: step 3 drawn by exabricks render against its data: max %.1f/255, mean %.3f/255, "
          "all %d steps drawn" % (255 * d.max(), 255 * d.mean(),
                                  sum(os.path.exists(os.path.join(out, "step_%04d.png" % k)) for k in range(5))))
    if d.max() > 1.0 / 255 or not all(os.path.exists(os.path.join(out, "step_%04d.png" % k)) for k in range(5)):
        failures.append("without a display the steps were not drawn as exabricks render draws them")

# A Catalyst script that fails (no plugin to load): reported, and the simulation goes on to its end.
run = simulate(2, os.path.join(work, "failing"), False)
steps = [line for line in run.stdout.splitlines() if line.startswith("step ")]
print("without the plugin: exit %d, %d steps, %d reporting the script's failure" %
      (run.returncode, len(steps), sum("failed" in s for s in steps)))
if run.returncode != 0 or len(steps) != 5:
    failures.append("a failing Catalyst script stopped the simulation (exit %d, %d steps)" % (run.returncode, len(steps)))
if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
