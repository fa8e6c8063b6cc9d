"""CPU time per lane of one BSDF call of the Mitsuba plugin's "tables" mode against the native
BSDF it stands for: eval, pdf, sample and eval_pdf on a wavefront of 2^20 random lanes
(directions uniform on the sphere for glass, on the upper hemisphere for gold; the smallest of
three timings after one that compiles the kernel), llvm_ad_rgb. Not part of `make test`; run by
hand (docs/benchmarks.md, "Rendering in Mitsuba 3", its transmissive table files):

    python3 python/tests/mitsuba_bsdf_calls.py GOLD_TAB GLASS_TAB [GLASS_TAB ...]

GOLD_TAB: the table file of mitsuba_scenes' gold (opaque), GLASS_TAB: of its rough glass (as
mitsuba_glass_tables.py leaves them in its OUTDIR).
"""

import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
import layerlab.mitsuba  # noqa: E402,F401
import mitsuba_scenes as S  # noqa: E402

N = 1 << 20


def _directions(rng, upper):
    v = rng.normal(size=(N, 3))
    v /= np.linalg.norm(v, axis=1)[:, None]
    if upper:
        v[:, 2] = np.abs(v[:, 2])
    return mi.Vector3f(*[mi.Float(np.ascontiguousarray(v[:, i]).astype(np.float32))
                         for i in range(3)])


def _per_lane(fn):
    dr.eval(fn())
    dr.sync_thread()
    times = []
    for _ in range(3):
        t = time.process_time()
        dr.eval(fn())
        dr.sync_thread()
        times.append(time.process_time() - t)
    return min(times) / N * 1e9


def main():
    gold, glass = sys.argv[1], sys.argv[2:]
    cases = [("native roughdielectric", S.native_bsdf("dielectric"), False)]
    cases += [("tables %s" % p, {"type": "layerlab", "filename": p}, False) for p in glass]
    cases += [("native roughconductor", S.native_bsdf("conductor"), True),
              ("tables %s" % gold, {"type": "layerlab", "filename": gold}, True)]
    rng = np.random.default_rng(1)
    ctx = mi.BSDFContext()
    for name, props, opaque in cases:
        bsdf = mi.load_dict(props)
        si = dr.zeros(mi.SurfaceInteraction3f, N)
        si.wi = _directions(rng, opaque)
        wo = _directions(rng, opaque)
        u = mi.Point2f(mi.Float(rng.uniform(size=N).astype(np.float32)),
                       mi.Float(rng.uniform(size=N).astype(np.float32)))
        calls = (("eval", lambda: bsdf.eval(ctx, si, wo)),
                 ("pdf", lambda: bsdf.pdf(ctx, si, wo)),
                 ("sample", lambda: bsdf.sample(ctx, si, mi.Float(0.5), u)[1]),
                 ("eval_pdf", lambda: bsdf.eval_pdf(ctx, si, wo)[0]))
        print("%-40s " % name + "  ".join("%s %.0f ns" % (k, _per_lane(fn)) for k, fn in calls),
              flush=True)


if __name__ == "__main__":
    main()
