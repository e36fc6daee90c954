"""A furnished living room modelled in Blender and written by Blender's own OBJ exporter.

    pip install bpy          # Blender as a Python module (5.0.1 made the committed files)
    python scenes/blender/make_living_room.py scenes/blender

writes living_room.obj and living_room.mtl exactly as Blender's File > Export > Wavefront
(.obj) writes them (materials on, modifiers applied, Y up, -Z forward): Principled BSDF
materials become Blender's MTL lines (Kd, Ks, Ns, Ni, d, illum and the PBR extensions Pr, Pm,
Ke), including the values other readers trip on (Ks 0 on materials whose specular level is 0,
Ni 1.0, a metal's Pm 1, glass's d and Ni). The room: walls, floor and ceiling around an open
window with a bright sky panel outside, a sofa with bevelled cushions, a coffee table with a
glass vase, a rug, a bookshelf of books, a framed picture, a standing lamp whose shade glows,
and a ceiling light. Nothing is random: the same script writes the same files.
"""

import math
import os
import sys

import bpy

OUT = sys.argv[-1] if len(sys.argv) > 1 and not sys.argv[-1].endswith(".py") else "."

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene


def material(name, color, roughness=0.5, metallic=0.0, specular=0.5, ior=1.5,
             transmission=0.0, alpha=1.0, emission=None, strength=0.0):
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    if bsdf is None:
        m.use_nodes = True
        bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular IOR Level"].default_value = specular
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["Alpha"].default_value = alpha
    if emission is not None:
        bsdf.inputs["Emission Color"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    return m


MATS = {
    "Wall": material("Wall", (0.78, 0.74, 0.66), roughness=0.9, specular=0.0),
    "Ceiling": material("Ceiling", (0.85, 0.85, 0.83), roughness=1.0, specular=0.0),
    "FloorWood": material("FloorWood", (0.42, 0.26, 0.14), roughness=0.35, specular=0.5),
    "Rug": material("Rug", (0.45, 0.12, 0.10), roughness=1.0, specular=0.0),
    "SofaFabric": material("SofaFabric", (0.20, 0.28, 0.42), roughness=0.95, specular=0.0),
    "Cushion": material("Cushion", (0.75, 0.62, 0.30), roughness=0.9, specular=0.0),
    "TableWood": material("TableWood", (0.30, 0.17, 0.08), roughness=0.25, specular=0.5),
    "Glass": material("Glass", (1.0, 1.0, 1.0), roughness=0.0, ior=1.5, transmission=1.0),
    "Brass": material("Brass", (0.91, 0.78, 0.42), roughness=0.3, metallic=1.0),
    "Canvas": material("Canvas", (0.55, 0.60, 0.50), roughness=1.0, specular=0.0),
    "Shelf": material("Shelf", (0.60, 0.50, 0.38), roughness=0.6, specular=0.5),
    "LampShade": material("LampShade", (0.9, 0.85, 0.7), roughness=1.0, specular=0.0,
                          emission=(1.0, 0.8, 0.55), strength=6.0),
    "CeilingLight": material("CeilingLight", (1, 1, 1), roughness=1.0, specular=0.0,
                             emission=(1.0, 0.95, 0.9), strength=12.0),
    "Sky": material("Sky", (0, 0, 0), roughness=1.0, specular=0.0,
                    emission=(0.75, 0.85, 1.0), strength=8.0),
    "Metal": material("Metal", (0.2, 0.2, 0.2), roughness=0.4, metallic=1.0),
}
BOOKS = [material(f"Book{i}", c, roughness=0.7, specular=0.3) for i, c in enumerate([
    (0.55, 0.10, 0.08), (0.10, 0.30, 0.15), (0.12, 0.15, 0.45), (0.70, 0.60, 0.20),
    (0.35, 0.20, 0.40), (0.80, 0.78, 0.70)])]


def assign(obj, mat):
    obj.data.materials.append(mat)


def box(name, size, loc, mat, bevel=0.0, segments=3, rot_z=0.0):
    """An axis-aligned box of `size` (x, y, z in metres) centred at `loc`, z up."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=loc, rotation=(0, 0, rot_z))
    obj = bpy.context.active_object
    obj.name = name
    obj.scale = size
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    if bevel > 0:
        mod = obj.modifiers.new("Bevel", "BEVEL")
        mod.width = bevel
        mod.segments = segments
    assign(obj, mat)
    return obj


def cylinder(name, radius, depth, loc, mat, vertices=32, cap=True):
    bpy.ops.mesh.primitive_cylinder_add(vertices=vertices, radius=radius, depth=depth,
                                        location=loc,
                                        end_fill_type="NGON" if cap else "NOTHING")
    obj = bpy.context.active_object
    obj.name = name
    assign(obj, mat)
    return obj


# --- the shell: 6 x 4.5 m, 2.7 m high; the window in the wall at y = 2.25 --------------
W, D, H, T = 6.0, 4.5, 2.7, 0.1
box("Floor", (W, D, T), (0, 0, -T / 2), MATS["FloorWood"])
box("Ceiling", (W, D, T), (0, 0, H + T / 2), MATS["Ceiling"])
box("WallWest", (T, D, H), (-W / 2 - T / 2, 0, H / 2), MATS["Wall"])
box("WallEast", (T, D, H), (W / 2 + T / 2, 0, H / 2), MATS["Wall"])
box("WallSouth", (W, T, H), (0, -D / 2 - T / 2, H / 2), MATS["Wall"])
# the north wall around a 1.8 x 1.3 m window opening centred at x = 0.8, sill at 0.9 m
wx, ww, sill, wh = 0.8, 1.8, 0.9, 1.3
left = (wx - ww / 2) - (-W / 2)
right = W / 2 - (wx + ww / 2)
box("WallNorthL", (left, T, H), (-W / 2 + left / 2, D / 2 + T / 2, H / 2), MATS["Wall"])
box("WallNorthR", (right, T, H), (W / 2 - right / 2, D / 2 + T / 2, H / 2), MATS["Wall"])
box("WallNorthLow", (ww, T, sill), (wx, D / 2 + T / 2, sill / 2), MATS["Wall"])
box("WallNorthHigh", (ww, T, H - sill - wh), (wx, D / 2 + T / 2, (H + sill + wh) / 2),
    MATS["Wall"])
# window frame bars and the sky outside
box("WindowBarV", (0.04, 0.06, wh), (wx, D / 2 + T / 2, sill + wh / 2), MATS["Metal"])
box("WindowBarH", (ww, 0.06, 0.04), (wx, D / 2 + T / 2, sill + wh / 2), MATS["Metal"])
bpy.ops.mesh.primitive_plane_add(size=1.0, location=(wx, D / 2 + 1.5, sill + wh / 2),
                                 rotation=(math.pi / 2, 0, 0))
sky = bpy.context.active_object
sky.name = "SkyPanel"
sky.scale = (ww * 2.5, wh * 2.5, 1)
assign(sky, MATS["Sky"])
# a closed box around the outside, so that the room is one closed scene
box("Outside", (W * 0.9, 0.05, H * 1.4), (wx, D / 2 + 1.6, sill + wh / 2), MATS["Wall"])

# --- the sofa against the south wall ----------------------------------------------------
sx, sy = -0.6, -D / 2 + 0.55
box("SofaBase", (2.2, 0.9, 0.42), (sx, sy, 0.21), MATS["SofaFabric"], bevel=0.04)
box("SofaBack", (2.2, 0.22, 0.55), (sx, sy - 0.34, 0.69), MATS["SofaFabric"], bevel=0.05)
for side in (-1, 1):
    box(f"SofaArm{side}", (0.2, 0.9, 0.62), (sx + side * 1.0, sy, 0.31), MATS["SofaFabric"],
        bevel=0.05)
for i in range(3):
    box(f"SeatCushion{i}", (0.62, 0.7, 0.14), (sx - 0.65 + 0.65 * i, sy + 0.06, 0.49),
        MATS["SofaFabric"], bevel=0.05, segments=4)
for i in range(2):
    box(f"BackCushion{i}", (0.45, 0.14, 0.4), (sx - 0.4 + 0.8 * i, sy - 0.18, 0.74),
        MATS["Cushion"], bevel=0.06, segments=4, rot_z=0.12 * (1 - 2 * i))

# --- the rug, the coffee table and its glass vase ----------------------------------------
box("Rug", (2.6, 1.8, 0.01), (sx, 0.0, 0.005), MATS["Rug"])
tx, ty = sx, 0.1
box("TableTop", (1.2, 0.6, 0.05), (tx, ty, 0.42), MATS["TableWood"], bevel=0.01)
for ix in (-1, 1):
    for iy in (-1, 1):
        cylinder(f"TableLeg{ix}{iy}", 0.025, 0.4, (tx + ix * 0.52, ty + iy * 0.24, 0.2),
                 MATS["TableWood"], vertices=16)
vase = cylinder("Vase", 0.07, 0.3, (tx + 0.3, ty, 0.595), MATS["Glass"], vertices=48)
solid = vase.modifiers.new("Solidify", "SOLIDIFY")
solid.thickness = 0.006
bpy.ops.mesh.primitive_uv_sphere_add(radius=0.09, segments=32, ring_count=16,
                                     location=(tx - 0.3, ty, 0.535))
bowl = bpy.context.active_object
bowl.name = "BrassBowl"
assign(bowl, MATS["Brass"])

# --- the bookshelf on the west wall, books on three shelves ------------------------------
bx, by = -W / 2 + 0.2, 0.6
box("ShelfSideA", (0.35, 0.03, 2.0), (bx, by - 0.6, 1.0), MATS["Shelf"])
box("ShelfSideB", (0.35, 0.03, 2.0), (bx, by + 0.6, 1.0), MATS["Shelf"])
for k in range(5):
    box(f"Shelf{k}", (0.35, 1.2, 0.03), (bx, by, 0.05 + 0.47 * k), MATS["Shelf"])
n = 0
for k in range(3):
    y = by - 0.56
    j = 0
    while y < by + 0.5:
        w = 0.03 + 0.012 * ((j * 7 + k * 3) % 4)
        h = 0.22 + 0.03 * ((j * 5 + k) % 3)
        box(f"Book{n}", (0.22, w, h), (bx + 0.02, y + w / 2, 0.065 + 0.47 * k + h / 2),
            BOOKS[(j + 2 * k) % len(BOOKS)], bevel=0.004, segments=2)
        y += w + 0.004
        j += 1
        n += 1

# --- a framed picture on the east wall ----------------------------------------------------
px, pz = W / 2 - 0.03, 1.5
box("PictureCanvas", (0.02, 1.0, 0.7), (px, 0.0, pz), MATS["Canvas"])
for s in (-1, 1):
    box(f"FrameV{s}", (0.04, 0.05, 0.8), (px - 0.01, s * 0.525, pz), MATS["Brass"], bevel=0.01)
    box(f"FrameH{s}", (0.04, 1.1, 0.05), (px - 0.01, 0.0, pz + s * 0.375), MATS["Brass"],
        bevel=0.01)

# --- a standing lamp in the corner, its shade glowing, and the ceiling light -------------
lx, ly = 1.2, -D / 2 + 0.45
cylinder("LampBase", 0.16, 0.03, (lx, ly, 0.015), MATS["Metal"], vertices=32)
cylinder("LampPole", 0.015, 1.5, (lx, ly, 0.78), MATS["Metal"], vertices=12)
bpy.ops.mesh.primitive_cone_add(vertices=48, radius1=0.25, radius2=0.15, depth=0.3,
                                location=(lx, ly, 1.6), end_fill_type="NOTHING")
shade = bpy.context.active_object
shade.name = "LampShade"
assign(shade, MATS["LampShade"])
bpy.ops.mesh.primitive_circle_add(vertices=64, radius=0.3, fill_type="NGON",
                                  location=(0.0, 0.0, H - 0.02))
light = bpy.context.active_object
light.name = "CeilingLight"
light.rotation_euler = (math.pi, 0, 0)
assign(light, MATS["CeilingLight"])

# --- a side cabinet under the window, with a plant --------------------------------------
box("Cabinet", (1.4, 0.4, 0.6), (wx, D / 2 - 0.25, 0.3), MATS["Shelf"], bevel=0.01)
cylinder("Pot", 0.12, 0.2, (wx + 0.45, D / 2 - 0.25, 0.7), MATS["Canvas"], vertices=32)
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=0.22,
                                      location=(wx + 0.45, D / 2 - 0.25, 0.98))
leaf = bpy.context.active_object
leaf.name = "Plant"
assign(leaf, material("Leaves", (0.10, 0.35, 0.08), roughness=0.6, specular=0.5))

os.makedirs(OUT, exist_ok=True)
bpy.ops.wm.obj_export(filepath=os.path.join(OUT, "living_room.obj"), export_materials=True,
                      apply_modifiers=True, forward_axis="NEGATIVE_Z", up_axis="Y",
                      export_selected_objects=False, export_uv=True, export_normals=True,
                      path_mode="RELATIVE")
print("wrote", os.path.join(OUT, "living_room.obj"))
