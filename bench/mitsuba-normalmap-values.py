"""Values of Mitsuba 3.9.1's `normalmap` around a `diffuse` (reflectance 0.5) with a
constant normal-map colour, at a few (normal, wi, wo): the BSDF's eval (with the cosine),
printed as the Rust table of the normal-map tests in src/texture/normal.rs, with the
shadowing term off (use_shadowing_function false) and on (Mitsuba's default).

The shading frame is the identity (n = z, dp/du = x); wi points towards the viewer, wo is
the scattered direction. Cases where wi is below the map's normal but above the smooth
surface show `flip_invalid_normals` (on by default): the normal mirrored about z.

Run with the Mitsuba venv: /work/mitsuba-venv/bin/python bench/mitsuba-normalmap-values.py"""
import math
import mitsuba as mi

mi.set_variant("scalar_rgb")


def unit(v):
    k = 1.0 / math.sqrt(sum(x * x for x in v))
    return [x * k for x in v]


CASES = [
    # (normal, wi, wo)
    (unit([1, 1, 1]), unit([-1, -1, 0.5]), [0, 0, 1]),  # wi below n: flipped
    (unit([1, 1, 1]), unit([1, 0.5, 0.5]), unit([-0.3, 0.2, 1])),  # wi above n: kept
    (unit([0.6, 0, 0.8]), unit([-1, 0.2, 0.4]), unit([0.5, 0.1, 0.6])),  # flipped
    (unit([0.6, 0, 0.8]), unit([0.2, 0.2, 1]), unit([-0.9, 0, 0.3])),  # wo below n
    (unit([0.3, -0.4, 0.5]), unit([0.1, 0.9, 0.3]), unit([0.4, -0.2, 0.9])),
]

print("// (normal, wi, wo, eval without the shadowing term, eval with it)")
ctx = mi.BSDFContext()
for n, wi, wo in CASES:
    vals = []
    for shadowing in (False, True):
        b = mi.load_dict({
            "type": "normalmap",
            "use_shadowing_function": shadowing,
            "normalmap": {"type": "bitmap", "raw": True, "filter_type": "nearest",
                          "data": mi.TensorXf([[[(x + 1) / 2 for x in n]]])},
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}},
        })
        si = mi.SurfaceInteraction3f()
        si.p = [0, 0, 0]
        si.n = [0, 0, 1]
        si.sh_frame = mi.Frame3f(si.n)
        si.dp_du = [1, 0, 0]
        si.dp_dv = [0, 1, 0]
        si.wi = wi
        si.uv = [0.5, 0.5]
        vals.append(b.eval(ctx, si, mi.Vector3f(wo))[0])
    fmt = lambda v: "[" + ", ".join(f"{x:.7e}" for x in v) + "]"
    print(f"    ({fmt(n)}, {fmt(wi)}, {fmt(wo)}, {vals[0]:.7e}, {vals[1]:.7e}),")
