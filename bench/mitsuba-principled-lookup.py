"""Mitsuba 3.9.1's `principled` and `principledthin` with every parameter a checkerboard,
evaluated where a ray hits a rectangle: the known answers of
src/scene/mitsuba/principled_tests.rs (`checkered_principled_agrees_with_mitsuba`).

Mitsuba reads base_color with the texture's `eval` and every scalar (roughness, metallic,
anisotropic, ...) with `eval_1`, and a checkerboard's `eval_1` takes color1 where its `eval`
takes color0: the checks of the scalars are the colour's shifted by one square. The script
prints, per BSDF and hit, the hit's uv, the ray's direction and the scattered direction
(world), and the BSDF's eval (with the cosine) per RGB channel.

Run with the Mitsuba venv: /work/mitsuba-venv/bin/python bench/mitsuba-principled-lookup.py
"""
import drjit as dr
import mitsuba as mi

mi.set_variant("scalar_rgb")


def checker(c0, c1):
    return {"type": "checkerboard", "color0": c0, "color1": c1}


PRINCIPLED = {
    "type": "principled",
    "base_color": checker({"type": "rgb", "value": [0.2, 0.8, 0.1]},
                          {"type": "rgb", "value": [0.9, 0.3, 0.5]}),
    "roughness": checker(0.15, 0.5),
    "anisotropic": checker(0.05, 0.8),
    "metallic": checker(0.7, 0.1),
    "spec_tint": checker(0.2, 0.6),
    "sheen": checker(0.2, 0.9),
    "sheen_tint": checker(0.3, 0.7),
    "flatness": checker(0.1, 0.6),
    "clearcoat": checker(0.9, 0.1),
    "clearcoat_gloss": checker(0.2, 0.8),
    "spec_trans": checker(0.3, 0.6),
    "specular": 0.7,
}
THIN = {
    "type": "principledthin",
    "base_color": checker({"type": "rgb", "value": [0.7, 0.1, 0.1]},
                          {"type": "rgb", "value": [0.2, 0.4, 0.9]}),
    "roughness": checker(0.3, 0.6),
    "anisotropic": checker(0.05, 0.8),
    "spec_tint": checker(0.2, 0.6),
    "sheen": checker(0.1, 0.8),
    "sheen_tint": checker(0.3, 0.7),
    "flatness": checker(0.1, 0.6),
    "spec_trans": checker(0.2, 0.8),
    "diff_trans": checker(0.4, 1.4),
    "eta": 1.33,
}

# (hit point on the rectangle [-1, 1]^2 x {0}, direction towards the viewer, scattered)
HITS = [
    ((-0.5, -0.5), (0.3, 0.2, 0.9), (-0.4, 0.1, 0.8)),   # uv (0.25, 0.25)
    ((0.5, -0.5), (0.3, 0.2, 0.9), (-0.4, 0.1, 0.8)),    # uv (0.75, 0.25)
    ((-0.5, -0.5), (0.3, 0.2, 0.9), (-0.3, -0.2, -0.8)),  # transmitted
    ((0.5, 0.5), (-0.2, 0.5, 0.7), (0.2, -0.3, -0.9)),   # uv (0.75, 0.75), transmitted
]


def main():
    for bsdf in (PRINCIPLED, THIN):
        scene = mi.load_dict({"type": "scene", "r": {"type": "rectangle", "bsdf": bsdf}})
        print(bsdf["type"])
        for (x, y), wi, wo in HITS:
            wi = dr.normalize(mi.Vector3f(wi))
            wo = dr.normalize(mi.Vector3f(wo))
            p = mi.Point3f(x, y, 0.0)
            ray = mi.Ray3f(p + 2.0 * wi, -wi)
            si = scene.ray_intersect(ray)
            v = si.bsdf().eval(mi.BSDFContext(), si, si.to_local(wo))
            print(f"  uv ({si.uv[0]:.4f}, {si.uv[1]:.4f}) wi {list(wi)} wo {list(wo)}")
            print(f"    eval (cos) [{v[0]:.7e}, {v[1]:.7e}, {v[2]:.7e}]")


if __name__ == "__main__":
    main()
