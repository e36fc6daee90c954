"""Mitsuba 3's image of a square area light whose radiance is a 2x2 bitmap (nearest
texels), seen straight on (tests/data/textured-area-light/): the known answer of
tests/textured_emission.rs (`mitsuba_quadrants`). Prints the 8x8 image's four centre
pixels.

    /work/mitsuba-venv/bin/python bench/textured-area-light.py
"""
import os

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
here = os.path.dirname(os.path.abspath(__file__))
scene = os.path.join(here, "..", "tests", "data", "textured-area-light", "scene.xml")
img = np.array(mi.render(mi.load_file(scene)))
for y, x in [(3, 3), (3, 4), (4, 3), (4, 4)]:
    print(f"pixel (x {x}, y {y}): {img[y, x]}")
