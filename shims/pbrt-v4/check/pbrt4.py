"""Running a pbrt-v4 binary the user has, and reading what it writes.

Nothing here builds pbrt-v4: the checks take the path of a binary
(`make pbrt4-check PBRT4=/path/to/pbrt`). Scenes are written to a work
directory and rendered to PFM (pbrt-v4 writes PFM for a `.pfm` film name;
a float format needs no image library here)."""

import os
import re
import subprocess
import time

import numpy as np


def read_pfm(path):
    """An (h, w, 3) float array, top row first, from a colour PFM file."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"PF":
            raise ValueError("%s: not a colour PFM file" % path)
        dims = f.readline().split()
        while len(dims) < 2:
            dims += f.readline().split()
        w, h = int(dims[0]), int(dims[1])
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    if data.size != w * h * 3:
        raise ValueError("%s: %d values for %d x %d pixels" % (path, data.size, w, h))
    # PFM stores the bottom row first.
    return data.reshape(h, w, 3)[::-1].astype(np.float64)


def render(pbrt, scene_text, work, name, seed=0, threads=None):
    """Render a scene given as text; return (image, wall seconds, CPU seconds
    of the pbrt process)."""
    os.makedirs(work, exist_ok=True)
    scene = os.path.join(work, name + ".pbrt")
    image = os.path.join(work, name + ".pfm")
    with open(scene, "w") as f:
        f.write(scene_text)
    if os.path.exists(image):
        os.unlink(image)
    command = [pbrt, "--quiet", "--seed", str(seed), "--outfile", image, scene]
    if threads:
        command[1:1] = ["--nthreads", str(threads)]
    before = os.times()
    start = time.perf_counter()
    run = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=work)
    wall = time.perf_counter() - start
    after = os.times()
    if run.returncode != 0 or not os.path.exists(image):
        raise RuntimeError("pbrt-v4 failed on %s (status %d):\n%s"
                           % (scene, run.returncode, run.stdout.decode(errors="replace")))
    cpu = (after.children_user - before.children_user) + \
        (after.children_system - before.children_system)
    return read_pfm(image), wall, cpu


def film(resolution, spp, image_name):
    """What every check scene shares: pbrt-v4's RGB film with the CIE 1931
    sensor (so a spectrum's RGB is the observer's, spectra.film_rgb), a box
    pixel filter (each pixel the mean over its area), independent samples,
    one bounce."""
    return """Film "rgb" "integer xresolution" [ %d ] "integer yresolution" [ %d ]
    "string sensor" "cie1931" "string filename" [ "%s" ]
PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]
Sampler "independent" "integer pixelsamples" [ %d ]
Integrator "path" "integer maxdepth" [ 1 ]
""" % (resolution, resolution, image_name, spp)


def quote(path):
    if '"' in path:
        raise ValueError("a scene cannot name a file with a double quote: %r" % path)
    return '"%s"' % path
