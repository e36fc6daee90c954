"""Values of Mitsuba 3.9.1's `principled` BSDF (eval, with the cosine, and pdf) at a few
direction pairs, printed as the Rust table of src/material/principled_tests.rs.

Run with the Mitsuba venv: /work/mitsuba-venv/bin/python bench/mitsuba-principled-values.py
(directions in the local frame: wi towards the viewer, wo the scattered direction)."""
import math
import mitsuba as mi

mi.set_variant("scalar_rgb")

CASES = [
    # (parameters, [(wi, wo)])
    ({"base_color": [0.2, 0.8, 0.1], "roughness": 0.15, "metallic": 0.7, "clearcoat": 0.9,
      "sheen": 0.2, "specular": 0.7}, None),
    ({"base_color": [0.3, 0.6, 0.8], "roughness": 0.4, "spec_trans": 0.7, "clearcoat": 0.6,
      "clearcoat_gloss": 0.3, "sheen": 0.9, "sheen_tint": 0.5, "spec_tint": 0.4,
      "specular": 0.4}, None),
    ({"base_color": [0.9, 0.5, 0.3], "roughness": 0.6, "flatness": 0.5, "eta": 1.33,
      "spec_trans": 0.3, "metallic": 0.2}, None),
]


def d(theta, phi):
    t, p = math.radians(theta), math.radians(phi)
    return [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]


PAIRS = [
    (d(30, 0), d(40, 180)),   # near the mirror direction
    (d(10, 0), d(60, 90)),
    (d(70, 0), d(20, 200)),
    (d(45, 0), d(150, 180)),  # transmission
    (d(160, 0), d(30, 180)),  # from inside, transmission
    (d(150, 0), d(140, 170)),  # from inside, reflection
]

print("// (parameters index, wi, wo, eval rgb, pdf)")
for k, (params, _) in enumerate(CASES):
    b = mi.load_dict({"type": "principled", **{
        n: ({"type": "rgb", "value": v} if isinstance(v, list) else v) for n, v in params.items()}})
    ctx = mi.BSDFContext()
    for wi, wo in PAIRS:
        si = mi.SurfaceInteraction3f()
        si.p = [0, 0, 0]
        si.n = [0, 0, 1]
        si.sh_frame = mi.Frame3f(si.n)
        si.wi = wi
        si.uv = [0.5, 0.5]
        f = b.eval(ctx, si, mi.Vector3f(wo))
        p = b.pdf(ctx, si, mi.Vector3f(wo))
        fmt = lambda v: "[" + ", ".join(f"{x:.7e}" for x in v) + "]"
        print(f"    ({k}, {fmt(wi)}, {fmt(wo)}, {fmt([f[0], f[1], f[2]])}, {float(p):.7e}),")
