"""kalos against Mitsuba 3 on each microfacet / Fresnel BSDF: a sphere under a constant
environment (and one case under an equirectangular map), same geometry, camera, depth.

Usage (from the repository root, after `cargo build --release`):
    export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1
    /tmp/mitsuba/bin/python bench/bsdf-vs-mitsuba.py [--spp 256] [--res 128] [--only NAME]

Prints a Markdown table: per case the mean of kalos and of Mitsuba over the sphere's
pixels (and over the image), their relative difference, and the per-pixel RMSE between
the two images next to the RMSE of two Mitsuba renders with different seeds at the same
spp (the noise floor: agreement means the kalos-Mitsuba RMSE is close to sqrt(2)/2... of
it, i.e. of the same size). Work files go to /tmp/bsdf-vs-mitsuba/.
"""
import argparse, json, math, os, subprocess, sys
import numpy as np
import mitsuba as mi

ap = argparse.ArgumentParser()
ap.add_argument('--spp', type=int, default=256)
ap.add_argument('--res', type=int, default=128)
ap.add_argument('--kalos', default='target/release/kalos')
ap.add_argument('--variant', default='llvm_ad_rgb')
ap.add_argument('--threads', type=int, default=2)
ap.add_argument('--only', default=None)
a = ap.parse_args()
mi.set_variant(a.variant)

W = a.res
TMP = '/tmp/bsdf-vs-mitsuba'
os.makedirs(TMP, exist_ok=True)
CAM = dict(origin=[0, 0.6, 4.0], target=[0, 0, 0], up=[0, 1, 0], fov=32.0)
MAX_DEPTH = 64   # Mitsuba's max_depth: path segments, in both

# ---- the sphere: a UV sphere of radius 1 with smooth vertex normals ----
def write_sphere(path, n_th=96, n_ph=192):
    v, vn, f = [], [], []
    for i in range(n_th + 1):
        th = math.pi * i / n_th
        for j in range(n_ph):
            ph = 2 * math.pi * j / n_ph
            p = (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
            v.append(p); vn.append(p)
    idx = lambda i, j: i * n_ph + (j % n_ph) + 1
    for i in range(n_th):
        for j in range(n_ph):
            a_, b, c, d = idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j)
            # counter-clockwise seen from outside (normal outwards)
            if i > 0: f.append((a_, b, d))
            if i < n_th - 1: f.append((b, c, d))
    with open(path, 'w') as fh:
        fh.write('mtllib sphere.mtl\nusemtl ball\n')
        for p in v: fh.write('v %.7f %.7f %.7f\n' % p)
        for p in vn: fh.write('vn %.7f %.7f %.7f\n' % p)
        for t in f: fh.write('f %d//%d %d//%d %d//%d\n' % (t[0], t[0], t[1], t[1], t[2], t[2]))
    with open(os.path.join(os.path.dirname(path), 'sphere.mtl'), 'w') as fh:
        fh.write('newmtl ball\nKd 0.5 0.5 0.5\n')

SPHERE = os.path.join(TMP, 'sphere.obj')
write_sphere(SPHERE)

# ---- an environment map: sky gradient, a bright sun, a coloured band ----
def write_envmap(path, w=256, h=128):
    u = (np.arange(w) + 0.5) / w
    v = np.arange(h) / (h - 1)
    U, V = np.meshgrid(u, v)
    img = np.zeros((h, w, 3), np.float32)
    img[..., 0] = 0.3 + 0.7 * (1 - V)
    img[..., 1] = 0.4 + 0.5 * (1 - V)
    img[..., 2] = 0.6 + 0.6 * (1 - V) * (0.5 + 0.5 * np.cos(2 * np.pi * U))
    sun = np.exp(-(((U - 0.3) / 0.03) ** 2 + ((V - 0.3) / 0.05) ** 2))
    img += 40.0 * sun[..., None] * np.array([1.0, 0.9, 0.7], np.float32)
    band = (np.abs(V - 0.65) < 0.04)
    img[band] *= np.array([0.2, 1.0, 0.2], np.float32)
    mi.Bitmap(img).write(path)

ENVMAP = os.path.join(TMP, 'sky.exr')
write_envmap(ENVMAP)

AU_ETA, AU_K = [0.143, 0.374, 1.442], [3.983, 2.385, 1.603]
CU_ETA, CU_K = [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]
KD = [0.6, 0.3, 0.1]
rgb = lambda c: {'type': 'rgb', 'value': c}

# name: (kalos model TOML, Mitsuba BSDF dict, env: None constant / 'map')
CASES = {
    'conductor (Cu)': (
        f'{{ type = "conductor", eta = {CU_ETA}, k = {CU_K} }}',
        {'type': 'conductor', 'eta': rgb(CU_ETA), 'k': rgb(CU_K)}, None),
    'roughconductor (Au, a 0.2)': (
        f'{{ type = "roughconductor", eta = {AU_ETA}, k = {AU_K}, alpha = 0.2 }}',
        {'type': 'roughconductor', 'distribution': 'ggx', 'alpha': 0.2, 'eta': rgb(AU_ETA), 'k': rgb(AU_K)}, None),
    'plastic': (
        '{ type = "plastic", eta = 1.49 }',
        {'type': 'plastic', 'int_ior': 1.49, 'ext_ior': 1.0, 'diffuse_reflectance': rgb(KD)}, None),
    'roughplastic (a 0.2)': (
        '{ type = "roughplastic", eta = 1.49, alpha = 0.2 }',
        {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': 0.2, 'int_ior': 1.49, 'ext_ior': 1.0,
         'diffuse_reflectance': rgb(KD)}, None),
    'roughplastic nonlinear (a 0.4)': (
        '{ type = "roughplastic", eta = 1.49, alpha = 0.4, nonlinear = true }',
        {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': 0.4, 'int_ior': 1.49, 'ext_ior': 1.0, 'nonlinear': True,
         'diffuse_reflectance': rgb(KD)}, None),
    'dielectric': (
        '{ type = "dielectric", eta = 1.5 }',
        {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}, None),
    'roughdielectric (a 0.2)': (
        '{ type = "roughdielectric", eta = 1.5, alpha = 0.2 }',
        {'type': 'roughdielectric', 'distribution': 'ggx', 'alpha': 0.2, 'int_ior': 1.5, 'ext_ior': 1.0}, None),
    'thindielectric': (
        '{ type = "thindielectric", eta = 1.5 }',
        {'type': 'thindielectric', 'int_ior': 1.5, 'ext_ior': 1.0}, None),
    'roughplastic (a 0.2), envmap': (
        '{ type = "roughplastic", eta = 1.49, alpha = 0.2 }',
        {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': 0.2, 'int_ior': 1.49, 'ext_ior': 1.0,
         'diffuse_reflectance': rgb(KD)}, 'map'),
    'roughconductor (Au, a 0.2), envmap': (
        f'{{ type = "roughconductor", eta = {AU_ETA}, k = {AU_K}, alpha = 0.2 }}',
        {'type': 'roughconductor', 'distribution': 'ggx', 'alpha': 0.2, 'eta': rgb(AU_ETA), 'k': rgb(AU_K)}, 'map'),
    # Beckmann: Mitsuba's default distribution (its dicts name none)
    'roughconductor Beckmann (Au, a 0.2)': (
        f'{{ type = "roughconductor", eta = {AU_ETA}, k = {AU_K}, alpha = 0.2, distribution = "beckmann" }}',
        {'type': 'roughconductor', 'alpha': 0.2, 'eta': rgb(AU_ETA), 'k': rgb(AU_K)}, None),
    'roughconductor Beckmann (Au, a 0.5), envmap': (
        f'{{ type = "roughconductor", eta = {AU_ETA}, k = {AU_K}, alpha = 0.5, distribution = "beckmann" }}',
        {'type': 'roughconductor', 'alpha': 0.5, 'eta': rgb(AU_ETA), 'k': rgb(AU_K)}, 'map'),
    'roughplastic Beckmann (a 0.2)': (
        '{ type = "roughplastic", eta = 1.49, alpha = 0.2, distribution = "beckmann" }',
        {'type': 'roughplastic', 'alpha': 0.2, 'int_ior': 1.49, 'ext_ior': 1.0,
         'diffuse_reflectance': rgb(KD)}, None),
    'roughdielectric Beckmann (a 0.2)': (
        '{ type = "roughdielectric", eta = 1.5, alpha = 0.2, distribution = "beckmann" }',
        {'type': 'roughdielectric', 'alpha': 0.2, 'int_ior': 1.5, 'ext_ior': 1.0}, None),
}
ENV_ROT = (20.0, 60.0)   # degrees about x, then about y

def kalos_render(name, model, env, out, spp):
    toml = os.path.join(TMP, 'scene.toml')
    with open(toml, 'w') as f:
        f.write(f'''[camera]
origin = {CAM['origin']}
target = {CAM['target']}
up = {CAM['up']}
fov = {CAM['fov']}

[render]
res = [{W}, {W}]
max_depth = {MAX_DEPTH}

[[objects]]
file = "sphere.obj"

[materials.ball]
kd = {KD}
model = {model}
''')
        if env == 'map':
            f.write(f'\n[environment]\nmap = "sky.exr"\nrotate = [{ENV_ROT[0]}, {ENV_ROT[1]}, 0]\n')
        else:
            f.write('\n[environment]\nradiance = [1, 1, 1]\n')
    # Mitsuba's path tracer plays Russian roulette from depth 5 on (rr_depth): the same here
    cmd = [a.kalos, 'render', toml, '--spp', str(spp), '--threads', str(a.threads), '--rr-min-depth', '5',
           '-o', out, '--quiet']
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f'kalos failed on {name}: {r.stderr.strip()}')

def mitsuba_scene(bsdf, env):
    s = {'type': 'scene',
         'integrator': {'type': 'path', 'max_depth': MAX_DEPTH},
         'sensor': {'type': 'perspective', 'fov': CAM['fov'], 'fov_axis': 'y',
                    'to_world': mi.ScalarTransform4f().look_at(origin=CAM['origin'], target=CAM['target'], up=CAM['up']),
                    'film': {'type': 'hdrfilm', 'width': W, 'height': W, 'rfilter': {'type': 'box'},
                             'pixel_format': 'rgb'},
                    'sampler': {'type': 'independent'}},
         'ball': {'type': 'obj', 'filename': SPHERE, 'bsdf': bsdf}}
    if env == 'map':
        T = mi.ScalarTransform4f().rotate([0, 1, 0], ENV_ROT[1]) @ mi.ScalarTransform4f().rotate([1, 0, 0], ENV_ROT[0])
        s['env'] = {'type': 'envmap', 'filename': ENVMAP, 'to_world': T}
    else:
        s['env'] = {'type': 'constant', 'radiance': rgb([1.0, 1.0, 1.0])}
    return mi.load_dict(s)

def read(path):
    return np.array(mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False))

# pixels whose centre ray hits the unit sphere (0.97: away from the tessellated rim)
def sphere_mask():
    o = np.array(CAM['origin'], float); t = np.array(CAM['target'], float); up = np.array(CAM['up'], float)
    fwd = (t - o) / np.linalg.norm(t - o)
    right = np.cross(fwd, up); right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    tan = math.tan(math.radians(CAM['fov']) / 2)
    ys, xs = np.mgrid[0:W, 0:W]
    px = (2 * (xs + 0.5) / W - 1) * tan
    py = (1 - 2 * (ys + 0.5) / W) * tan
    d = fwd[None, None] + px[..., None] * right + py[..., None] * upv
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    b = (d * o).sum(-1)
    disc = b * b - (o @ o - 0.97 ** 2)
    return disc > 0

mask = sphere_mask()
rows = []
for name, (model, bsdf, env) in CASES.items():
    if a.only and a.only not in name:
        continue
    k_out = os.path.join(TMP, 'kalos.exr')
    kalos_render(name, model, env, k_out, a.spp)
    K = read(k_out)
    scene = mitsuba_scene(bsdf, env)
    M = np.array(mi.render(scene, spp=a.spp, seed=1))
    M2 = np.array(mi.render(scene, spp=a.spp, seed=2))
    km, mm = K[mask].mean(), M[mask].mean()
    rel = (km - mm) / mm
    rmse = math.sqrt(((K - M)[mask] ** 2).mean())
    floor = math.sqrt(((M2 - M)[mask] ** 2).mean())
    rows.append((name, km, mm, rel, K.mean(), M.mean(), rmse, floor))
    print(f'{name}: kalos {km:.5f} mitsuba {mm:.5f} ({100 * rel:+.2f}%), RMSE {rmse:.4f} (Mitsuba vs Mitsuba {floor:.4f})',
          file=sys.stderr, flush=True)

print(f'\n{W}x{W}, {a.spp} spp, max depth {MAX_DEPTH}; means over the sphere\'s pixels (all channels)\n')
print('| BSDF | kalos | Mitsuba 3 | difference | image mean kalos / Mitsuba | RMSE kalos-Mitsuba | RMSE Mitsuba-Mitsuba |')
print('|---|---|---|---|---|---|---|')
for (name, km, mm, rel, ki, mi_, rmse, floor) in rows:
    print(f'| {name} | {km:.4f} | {mm:.4f} | {100 * rel:+.2f}% | {ki:.4f} / {mi_:.4f} | {rmse:.4f} | {floor:.4f} |')
bad = [r[0] for r in rows if abs(r[3]) > 0.01]
if bad:
    print(f'\nMEAN DIFFERS BY MORE THAN 1%: {", ".join(bad)}')
    sys.exit(1)
