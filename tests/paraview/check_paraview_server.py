"""The ExaBricks representation in client-server mode: a render server of 2 processes (pvserver
under mpiexec, IceT compositing) and a pvpython client, against pvpython's own one-process
session:

    python3 check_paraview_server.py PLUGIN EXABRICKS_CLI WORK_DIR MPIEXEC PVSERVER PVPYTHON [DATA_DIR]

The server listens on a free port of localhost; the client loads the plugin on both sides. The
bounds are those of check_paraview_parallel.py. Prints "skipped: ..." where the shared sample is
absent."""
import json
import os
import socket
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pv_common import finest_cell, plotfile_or_skip, read_png  # noqa: E402

plugin, cli, work, mpiexec, pvserver, pvpython = sys.argv[1:7]
plotfile = plotfile_or_skip(sys.argv[7] if len(sys.argv) > 7 else None)
client = os.path.join(os.path.dirname(os.path.abspath(__file__)), "render_client.py")
os.makedirs(work, exist_ok=True)
settings = os.path.join(work, "settings.json")
with open(settings, "w") as f:
    json.dump({"plotfile": plotfile, "cell": finest_cell(cli, plotfile)}, f)

failures = []
reference = os.path.join(work, "builtin.png")
run = subprocess.run([pvpython, client, plugin, settings, reference], capture_output=True, text=True, timeout=300)
if run.returncode != 0:
    print(run.stdout[-2000:], run.stderr[-2000:])
    failures.append("pvpython's own session failed (exit %d)" % run.returncode)

with socket.socket() as s:  # a free port (the server binds it a moment later)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
command = [mpiexec, "--oversubscribe", "-np", "2"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
log = open(os.path.join(work, "server.log"), "w")
server = subprocess.Popen(command + [pvserver, "--server-port=%d" % port], stdout=log, stderr=subprocess.STDOUT)
try:
    deadline = time.time() + 60
    while time.time() < deadline:
        with open(os.path.join(work, "server.log")) as f:
            if "Accepting connection" in f.read():
                break
        time.sleep(0.2)
    remote = os.path.join(work, "server.png")
    run = subprocess.run([pvpython, client, plugin, settings, remote, str(port)], capture_output=True, text=True,
                         timeout=300)
    print(run.stdout.strip().splitlines()[-1] if run.stdout.strip() else "")
    if run.returncode != 0:
        print(run.stdout[-2000:], run.stderr[-2000:])
        failures.append("the client of a 2-process server failed (exit %d)" % run.returncode)
finally:
    server.terminate()
    try:
        server.wait(timeout=30)
    except subprocess.TimeoutExpired:
        server.kill()
    log.close()

if not failures:
    one, two = read_png(reference), read_png(remote)
    d = np.abs(one - two).max(axis=-1)
    shown = (one.max(axis=-1) > 0.02).mean()
    beyond, far = (d > 1.5 / 255 + 1e-9).mean(), (d > 4.5 / 255 + 1e-9).mean()
    print("2-process server against one process: max %.0f/255, mean %.3f/255, %.2f%% of pixels beyond 1.5/255, "
          "%.3f%% beyond 4.5/255 (%.0f%% showing data)" % (255 * d.max(), 255 * d.mean(), 100 * beyond, 100 * far,
                                                          100 * shown))
    if shown < 0.05 or d.mean() > 0.5 / 255 or beyond > 0.08 or far > 0.001:
        failures.append("the server's picture differs from one process's")
if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("passed")
