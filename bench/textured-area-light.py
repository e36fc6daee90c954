"""Mitsuba 3's image of a square area light whose radiance is a 2x2 bitmap (nearest
texels: red, green at the top, blue, yellow below in the image), seen straight on: the
known answer of tests/textured_emission.rs (`mitsuba_quadrants`), which writes the same
PFM and XML. Prints the 8x8 image's four centre pixels.

    /work/mitsuba-venv/bin/python bench/textured-area-light.py
"""
import os
import struct
import tempfile

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
d = tempfile.mkdtemp()
with open(os.path.join(d, "quad.pfm"), "wb") as f:
    f.write(b"PF\n2 2\n-1.0\n")
    # rows bottom to top
    for c in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0)]:
        f.write(struct.pack("<3f", *c))
with open(os.path.join(d, "scene.xml"), "w") as f:
    f.write("""<scene version="3.0.0">
  <integrator type="path"/>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
      <rfilter type="box"/><string name="pixel_format" value="rgb"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area">
      <texture name="radiance" type="bitmap">
        <string name="filename" value="quad.pfm"/>
        <string name="filter_type" value="nearest"/>
      </texture>
    </emitter>
  </shape>
</scene>""")
img = np.array(mi.render(mi.load_file(os.path.join(d, "scene.xml"))))
for y, x in [(3, 3), (3, 4), (4, 3), (4, 4)]:
    print(f"pixel (x {x}, y {y}): {img[y, x]}")
