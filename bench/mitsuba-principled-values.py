"""Values of Mitsuba 3.9.1's `principled` and `principledthin` BSDFs (eval, with the
cosine, and pdf) at a few direction pairs, printed as the Rust tables of
src/material/principled_tests.rs and src/material/principled_thin_tests.rs.

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
    # anisotropic main lobes (alpha_x along the shading frame's s = +x), at azimuths off
    # the frame's axes
    ({"base_color": [0.7, 0.4, 0.2], "roughness": 0.5, "anisotropic": 0.8, "metallic": 0.3,
      "spec_trans": 0.4, "clearcoat": 0.3, "sheen": 0.2}, "ANISO"),
    ({"base_color": [0.2, 0.5, 0.9], "roughness": 0.3, "anisotropic": 1.0, "spec_trans": 0.8,
      "spec_tint": 0.5, "eta": 1.4}, "ANISO"),
    # specular 0 without spec_trans: eta 1, where the dielectric Fresnel term is exactly 0
    # and the main reflection lobe (its metallic part too) is off
    ({"base_color": [0.2, 0.8, 0.1], "roughness": 0.15, "metallic": 0.7, "clearcoat": 0.9,
      "sheen": 0.2, "specular": 0.0}, "ETA1"),
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
ANISO = [
    (d(30, 40), d(35, 250)),
    (d(50, 120), d(60, 290)),
    (d(20, 0), d(55, 160)),
    (d(40, 30), d(150, 230)),  # transmission
    (d(140, 60), d(30, 250)),  # from inside, transmission
    (d(150, 20), d(140, 190)),  # from inside, reflection
]

# reflections at eta 1, grazing (wi.wh below 1/2, where the dielectric formula's rounding
# residue is mostly not exactly 0 in single precision) (and the inside, where Mitsuba's pdf is NaN, left out)
ETA1 = [
    (d(30, 0), d(40, 180)),
    (d(70, 0), d(70, 180)),
    (d(80, 0), d(75, 180)),
    (d(60, 0), d(80, 170)),
    (d(85, 0), d(85, 180)),
    (d(75, 30), d(65, 200)),
    (d(65, 0), d(72, 150)),
    (d(78, 10), d(60, 175)),
]

# principledthin: both hemispheres of wo from both sides (it transmits)
THIN_CASES = [
    ({"base_color": [0.7, 0.1, 0.1], "roughness": 0.5, "anisotropic": 0.8, "spec_trans": 0.6,
      "diff_trans": 1.4, "sheen": 0.8, "eta": 1.33}, "ANISO"),
    ({"base_color": [0.3, 0.6, 0.8], "roughness": 0.3, "spec_trans": 0.3, "diff_trans": 0.4,
      "spec_tint": 0.5, "sheen": 0.3, "sheen_tint": 0.6, "flatness": 0.4, "eta": 1.5}, None),
    ({"base_color": [0.9, 0.8, 0.2], "roughness": 0.6, "anisotropic": 0.3, "spec_trans": 0.9,
      "eta": 1.2}, "ANISO"),
]


def table(plugin, cases):
    print(f"// {plugin}: (parameters index, wi, wo, eval rgb, pdf)")
    for k, (params, pairs) in enumerate(cases):
        b = mi.load_dict({"type": plugin, **{
            n: ({"type": "rgb", "value": v} if isinstance(v, list) else v)
            for n, v in params.items()}})
        ctx = mi.BSDFContext()
        for wi, wo in {"ANISO": ANISO, "ETA1": ETA1}.get(pairs, PAIRS):
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


table("principled", CASES)
table("principledthin", THIN_CASES)
