#!/usr/bin/env python3
"""Particles with the gas: frame time of a volume alone and of the same volume with N particles
drawn as spheres, in one run, at one size; the sphere hierarchy's build time and the memory per
particle. Not a test.

usage: PYTHONPATH=build/python python3 bench/particles.py EXABRICKS [--cells 5000000]
           [--particles 10000000] [--size 1024] [--frames 3]

The volume is the generated `cosmic` scene; the particles lie where its gas is dense (positions
drawn from the cells in proportion to their value), with a mass and a temperature, coloured by
temperature on a logarithmic map, each about a pixel across.
"""
import argparse
import os
import resource
import subprocess
import tempfile
import time

import numpy as np

import exabricks


def particles_in_the_gas(ds, n, seed=1, grid=96):
    """n positions where the gas is: the field sampled on a grid of cells, each cell chosen in
    proportion to its value, and a uniform position within it."""
    rng = np.random.default_rng(seed)
    lo, hi = (np.array(b) for b in ds.bounds)
    axes = [lo[a] + (np.arange(grid) + 0.5) * (hi[a] - lo[a]) / grid for a in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    v, _ = ds.sample(centres)
    w = np.nan_to_num(v, nan=0.0).clip(min=0.0)
    cells = rng.choice(len(centres), size=n, p=w / w.sum())
    return centres[cells] + rng.uniform(-0.5, 0.5, (n, 3)) * (hi - lo) / grid


def frame_seconds(scene, size, frames):
    scene.render(64, 64)  # set-up (the sphere hierarchy, gradients) outside the timing
    times = []
    for i in range(frames):
        scene.seed = i + 1  # another frame: a view that holds this one's passes would not render
        t = time.perf_counter()
        scene.render(size, size)
        times.append(time.perf_counter() - t)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exabricks")
    ap.add_argument("--cells", type=int, default=5_000_000)
    ap.add_argument("--particles", type=int, default=10_000_000)
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--picture", help="write the last frame with particles here (PNG)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "cosmic.cells")
        subprocess.run([a.exabricks, "-q", "generate", "-s", "cosmic", "-n", str(a.cells), "-o", path], check=True)
        ds = exabricks.load(path)
        t = time.perf_counter()
        pos = particles_in_the_gas(ds, a.particles)
        rng = np.random.default_rng(2)
        temperature = 10 ** rng.uniform(3, 7, len(pos))
        print("%d cells, %d particles placed in %.1f s" % (ds.cells, len(pos), time.perf_counter() - t))
        rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        ds.add_particles("dark_matter", pos, mass=np.ones(len(pos)), temperature=temperature)
        del pos, temperature
        scene = exabricks.Scene(ds)
        alone = frame_seconds(scene, a.size, a.frames)
        scene.particles = True
        # About a pixel across at this size: most rays pass between the spheres, through the
        # hierarchy and on into the gas (the costly case; larger spheres end rays early).
        lo, hi = (np.array(b) for b in ds.bounds)
        scene.particle_radius = float(np.linalg.norm(hi - lo)) / a.size / 2.0
        scene.particle_color_by = "temperature"
        scene.particle_color_map = exabricks.TransferFunction("inferno", log=True)
        t = time.perf_counter()
        update = scene._update()
        build = time.perf_counter() - t
        rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        both = frame_seconds(scene, a.size, a.frames)
        print("size %d², %d threads (best of %d frames)" % (a.size, os.cpu_count(), a.frames))
        print("  volume alone          %.3f s" % alone)
        print("  volume + particles    %.3f s   ratio %.2f (goal <= 1.5)" % (both, both / alone))
        print("  sphere hierarchy      %.2f s to build (scene update %.2f s)" % (build, update["seconds"]))
        print("  peak memory growth    %.0f bytes per particle (arrays given, read copy, spheres, hierarchy,"
              " colours)" % ((rss1 - rss0) * 1024.0 / a.particles))
        if a.picture:
            scene.save(a.picture)


if __name__ == "__main__":
    main()
