#!/usr/bin/python3
"""Time to the first picture of `exabricks view`: from the start of the process to its address
on stdout, and to the first frame on its frame stream (what of the data it shows, where not all),
with the process's peak resident memory so far; then, optionally, to the first frame drawn from
every level and to the last, refined one.

    /usr/bin/python3 bench/first_picture.py build/exabricks INPUT [--size 512x512] [--every-level]
        [more options of exabricks view, such as --memory-budget 2G]
"""
import argparse
import http.client
import json
import struct
import subprocess
import sys
import tempfile
import time
import urllib.parse


def peak_rss_mib(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exabricks")
    ap.add_argument("input")
    ap.add_argument("--size", default="512x512")
    ap.add_argument("--every-level", action="store_true", help="wait for a frame drawn from every level")
    ap.add_argument("--timeout", type=float, default=3600)
    a, more = ap.parse_known_args()  # the rest goes to exabricks view
    more = [m for m in more if m != "--"]
    log = tempfile.TemporaryFile(mode="w+")
    started = time.time()
    view = subprocess.Popen([a.exabricks, "-q", "view", a.input, "--port", "0", "--size", a.size] + more,
                            stdout=subprocess.PIPE, stderr=log, text=True)
    try:
        line = view.stdout.readline().strip()
        address = time.time() - started
        if not line.startswith("http://"):
            view.wait()
            log.seek(0)
            sys.exit("the viewer printed no address (%r): %s" % (line, log.read()[-2000:]))
        url = urllib.parse.urlparse(line)
        token = urllib.parse.parse_qs(url.query)["token"][0]
        conn = http.client.HTTPConnection(url.hostname, url.port, timeout=a.timeout)
        conn.request("GET", "/api/stream", headers={"X-Exabricks-Token": token})
        r = conn.getresponse()
        first = every = None
        shows = ""
        while True:
            header = json.loads(r.read(struct.unpack("<I", r.read(4))[0]))
            r.read(struct.unpack("<I", r.read(4))[0])
            if header.get("keepalive") or "error" in header:
                continue
            now = time.time() - started
            if first is None:
                first, shows = now, header.get("data", "every level")
                first_peak = peak_rss_mib(view.pid)
            if not a.every_level:
                break
            # Every level: a frame without a data note, or one drawn from every level in parts
            # (under a memory budget: first after one pass, then refined to the last pass).
            if "data" not in header or header["data"].startswith("every level"):
                every = every or now
                if header.get("final"):
                    break
        result = {"address_s": round(address, 3), "first_frame_s": round(first, 3), "first_frame_shows": shows,
                  "peak_rss_mib_at_first_frame": round(first_peak, 1)}
        if a.every_level:
            result["every_level_s"] = round(every, 3)
            result["every_level_final_s"] = round(now, 3)
            result["peak_rss_mib"] = round(peak_rss_mib(view.pid), 1)
        print(json.dumps(result, indent=1))
    finally:
        view.terminate()
        view.wait()


if __name__ == "__main__":
    main()
