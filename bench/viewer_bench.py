#!/usr/bin/python3
"""Interactive figures of `exabricks view`, measured through a real browser (headless Chromium):

- latency: from a transfer-function edit or a camera drag (the input event in the page) to the
  first draft frame drawn on the page;
- draft frames per second drawn while the user orbits continuously;
- time from the end of an interaction to the refined full-resolution image on the page, against
  the command line's frame time for the same scene (`render --scene ... --stats`).

    /usr/bin/python3 bench/viewer_bench.py build/exabricks DATASET [--size 1024 | --size 1060x807] [--spp 1]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.parse

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By


def parse_arguments():
    ap = argparse.ArgumentParser()
    ap.add_argument("exabricks")
    ap.add_argument("input", nargs="?", default="")
    ap.add_argument("--size", default="1024", help="N (N x N pixels) or WxH")
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--orbit-seconds", type=float, default=4.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", action="store_true")
    return ap.parse_args()


def frame_size(a):
    """--size as the command line's WxH."""
    if a.size.isdigit():
        return "%sx%s" % (a.size, a.size)
    w, _, h = a.size.partition("x")
    if not (w.isdigit() and h.isdigit()):
        raise SystemExit("viewer_bench.py: error: --size %s is neither N nor WxH" % a.size)
    return a.size


def start_browser():
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for o in ["--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1500,1200"]:
        options.add_argument(o)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    driver.set_script_timeout(300)
    return driver


def wait_final(driver, after_request, timeout=300):
    """Waits inside the page for a refined frame newer than the request (no polling over
    the WebDriver, whose round trips would take CPU from the render)."""
    h = driver.execute_async_script("""
        const [after, done] = arguments;
        const latest = window.exabricksViewer.latest;
        if (latest && latest.final && latest.request > after) { done(latest); return; }
        window.addEventListener('exabricks-frame', function on(e) {
          if (e.detail.final && e.detail.request > after) {
            window.removeEventListener('exabricks-frame', on);
            done(e.detail);
          }
        });
    """, after_request)
    if not h:
        raise SystemExit("no refined frame")
    return h


def cli_frame(a, url, token, tmp):
    """The command line's frame for the scene on the page: a fresh process, like the viewer's
    first pass after a change, run right after the viewer's refinement (the pair shares the
    machine's state)."""
    scene = pathlib.Path(tmp) / "scene.json"
    scene.write_text(subprocess.run(["curl", "-s", "-H", "X-Exabricks-Token: " + token,
                                     url.split("/?")[0] + "/api/scene"], capture_output=True,
                                    text=True).stdout)
    out = subprocess.run([a.exabricks, "-q", "render", "--scene", str(scene), "-o",
                          str(pathlib.Path(tmp) / "x.png"), "--json"], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout)["frame_seconds"]


def measure_tf_edits(a, driver, request, cli):
    """Transfer-function edits: drag the last opacity point a little, then release; repeat. The
    latencies, the times to the refined image, the command line's frames and the last request."""
    js = driver.execute_script
    editor = driver.find_element(By.ID, "tf-editor")
    tf_latency, tf_final, cli_frames = [], [], []
    for i in range(a.repeats):
        n0 = len(js("return window.exabricksViewer.metrics.latencies"))
        pts = js("return window.exabricksViewer.doc.layers[0].transfer_function.opacity")
        x, y = pts[-1][0], pts[-1][1]
        w, h = editor.size["width"], editor.size["height"]
        px = (4 + x * 292) * w / 300 - w / 2
        py = (4 + (1 - y) * 110) * h / 130 - h / 2
        ActionChains(driver).move_to_element_with_offset(editor, px, py).click_and_hold() \
            .move_by_offset(0, 6 if i % 2 == 0 else -6).pause(0.3).release().perform()
        done = wait_final(driver, request)
        request = done["request"]
        lat = js("return window.exabricksViewer.metrics.latencies")
        tf_latency.extend(lat[n0:n0 + 1])
        tf_final.append(js("return window.exabricksViewer.metrics.finals")[-1]["ms"])
        cli_frames.append(cli())
    return tf_latency, tf_final, cli_frames, request


def measure_orbit(a, driver, request):
    """Orbit continuously for a few seconds: drafts drawn per second, latency of the first, and the
    time from the end to the refined image."""
    js = driver.execute_script
    n0 = len(js("return window.exabricksViewer.metrics.latencies"))
    d0 = len(js("return window.exabricksViewer.metrics.draftFrames"))
    # The drag is synthesised inside the page at 60 events per second (the WebDriver's own
    # actions arrive far slower), through the same pointer handlers a mouse uses.
    t0 = time.time()
    driver.execute_async_script("""
        const [seconds, done] = arguments;
        const c = document.getElementById('image');
        const r = c.getBoundingClientRect();
        let x = r.left + r.width / 2, y = r.top + r.height / 2;
        const ev = (type) => c.dispatchEvent(new PointerEvent(type, {clientX: x, clientY: y, button: 0,
                                                                        pointerId: 1, bubbles: true}));
        ev('pointerdown');
        const start = performance.now();
        const timer = setInterval(() => {
          x += 2;
          ev('pointermove');
          if (performance.now() - start > seconds * 1000) {
            clearInterval(timer);
            ev('pointerup');
            done();
          }
        }, 16);
    """, a.orbit_seconds)
    orbit_seconds = time.time() - t0
    drafts = js("return window.exabricksViewer.metrics.draftFrames")[d0:]
    span = (drafts[-1] - drafts[0]) / 1000 if len(drafts) > 1 else 0
    orbit_fps = (len(drafts) - 1) / span if span > 0 else 0
    orbit_latency = js("return window.exabricksViewer.metrics.latencies")[n0:n0 + 1]
    wait_final(driver, request)
    orbit_final = js("return window.exabricksViewer.metrics.finals")[-1]["ms"]
    draft_res = js("return window.exabricksViewer.latest")
    return {"orbit_to_first_draft_ms": orbit_latency, "orbit_drafts_per_second": orbit_fps,
            "orbit_drafts": len(drafts), "orbit_seconds": orbit_seconds, "orbit_end_to_refined_ms": orbit_final,
            "last_frame": draft_res}


def measure(a, driver, url):
    # A square size through the page's resolution choice, another through the scene's own size.
    driver.get(url + "&size=" + (a.size if a.size.isdigit() else "scene"))
    token = urllib.parse.parse_qs(urllib.parse.urlparse(url).query)["token"][0]
    tmp = tempfile.mkdtemp()

    def cli():
        return cli_frame(a, url, token, tmp)

    first = wait_final(driver, 0)
    driver.find_element(By.ID, "image")
    tf_latency, tf_final, cli_frames, request = measure_tf_edits(a, driver, first["request"], cli)
    orbit = measure_orbit(a, driver, request)
    cli_frames.append(cli())
    ratios = [v / 1000 / c for v, c in zip(tf_final + [orbit["orbit_end_to_refined_ms"]], cli_frames)]
    return {
        "size": a.size, "samples_per_pixel": a.spp,
        "tf_edit_to_first_draft_ms": tf_latency,
        "tf_edit_to_refined_ms": tf_final,
        "orbit_to_first_draft_ms": orbit["orbit_to_first_draft_ms"],
        "orbit_drafts_per_second": orbit["orbit_drafts_per_second"], "orbit_drafts": orbit["orbit_drafts"],
        "orbit_seconds": orbit["orbit_seconds"],
        "orbit_end_to_refined_ms": orbit["orbit_end_to_refined_ms"],
        "cli_frame_seconds": cli_frames,
        "refined_over_cli": ratios,
        "refined_over_cli_median": statistics.median(ratios),
        "last_frame": orbit["last_frame"],
    }


def print_results(a, results):
    if a.json:
        print(json.dumps(results, indent=2))
    else:
        print("viewer at %s, %d sample(s) per pixel" % (frame_size(a), a.spp))
        print("  TF edit -> first draft on the page   %s ms" % ", ".join("%.0f" % v for v in results["tf_edit_to_first_draft_ms"]))
        print("  orbit start -> first draft           %s ms" % ", ".join("%.0f" % v for v in results["orbit_to_first_draft_ms"]))
        print("  drafts per second while orbiting     %.1f (%d drafts)" % (results["orbit_drafts_per_second"], results["orbit_drafts"]))
        print("  end of edit -> refined image         %s ms" % ", ".join("%.0f" % v for v in results["tf_edit_to_refined_ms"] + [results["orbit_end_to_refined_ms"]]))
        print("  command line frame, after each       %s ms" % ", ".join("%.0f" % (v * 1000) for v in results["cli_frame_seconds"]))
        print("  refined / command line               %s (median %.3f)" % (", ".join("%.3f" % r for r in results["refined_over_cli"]), results["refined_over_cli_median"]))


def main():
    a = parse_arguments()
    args = [a.exabricks, "view", "--port", "0", "--spp", str(a.spp), "--size", frame_size(a)]
    if a.input:
        args.insert(2, a.input)
    server = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    url = server.stdout.readline().strip()
    driver = start_browser()
    results = {}
    try:
        results = measure(a, driver, url)
    finally:
        driver.quit()
        server.terminate()
        server.wait()
    print_results(a, results)
    return 0

if __name__ == "__main__":
    sys.exit(main())
