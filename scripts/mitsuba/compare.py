#!/usr/bin/env python3
"""cltrace against a peer: Mitsuba 3 renders the same small scenes, and the converged images
must agree region by region within the noise of the two estimates plus a 1% bias allowance.

One description per scene (SCENES below) is written out as the files both renderers read:
one OBJ per object (triangles, no normals; MTL materials `Kd`/`Ke`, a `map_Kd` texture) and
a cltrace scene file (scene.toml: the meshes, [camera] and [render], and where a scene has
them [environment] and [[light]]); Mitsuba loads the same OBJ files, with a bsdf and an area
emitter per object from the same materials, and the same environment (an envmap of the same
texels, or a constant) and point, spot and directional lights.

    compare.py scenes    --out DIR                       the cltrace inputs only
    compare.py reference --out DIR [--spp N] [--size WxH] inputs + Mitsuba references
    compare.py check     --cltrace BIN --refs DIR [--spp N]
    compare.py speed     --cltrace BIN [--devices D,D] [--variant V]   samples/s, both renderers

`scenes` needs only numpy; `reference` needs Mitsuba (scripts/mitsuba/setup.sh installs it),
and so does `check`, which reads the EXR files through Mitsuba's Bitmap. The tolerance and
the correspondence of settings are in scripts/mitsuba/README.md.
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time
import zlib

import numpy as np

MITSUBA_VARIANT = "scalar_rgb"
SIGMAS = 4.0  # how many standard deviations of the difference the check allows
BIAS = 0.01  # plus this share of Mitsuba's value
TILES = 2  # each object is checked in each of TILES x TILES parts of the image
SUBSAMPLES = 4  # a pixel belongs to a region when all SUBSAMPLES^2 of its probe rays agree
UNCHECKED = 255  # regions.png value of pixels that are not checked


# ---------------------------------------------------------------------------------------------
# The scenes: objects (triangles with a material), camera, depth.


def quad(p0, p1, p2, p3, uv=None):
    """Two triangles (p0 p1 p2) (p0 p2 p3): the front face is the side from which p0 p1 p2
    run counter-clockwise (the normal (p1 - p0) x (p2 - p0))."""
    tris = [(p0, p1, p2), (p0, p2, p3)]
    if uv is None:
        return tris, None
    return tris, [(uv[0], uv[1], uv[2]), (uv[0], uv[2], uv[3])]


def box(lo, hi):
    """An axis-aligned box, six faces facing out, corners not shared between faces."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = [
        ((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)),  # +z
        ((x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)),  # -z
        ((x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)),  # +x
        ((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)),  # -x
        ((x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)),  # +y
        ((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)),  # -y
    ]
    tris = []
    for f in faces:
        tris += quad(*f)[0]
    return tris


def uv_sphere(center, radius, segments, rings, closed=False):
    """A UV sphere of flat triangles (faces facing out); the poles are fans. Without
    `closed`, each pole's fan is degenerate (its triangles have two corners on the pole), so
    that the sphere is open there: the diffuse `sphere` scene's references were made so and
    are kept; the scenes of other materials (a dielectric needs a closed surface) close it."""
    cx, cy, cz = center

    def point(i, j):
        if closed:
            # One point per vertex: the seam's (i = segments) is i = 0's, the poles exact.
            i %= segments
            if j in (0, rings):
                return (cx, cy + (radius if j == 0 else -radius), cz)
        theta = math.pi * j / rings
        phi = 2.0 * math.pi * i / segments
        return (
            cx + radius * math.sin(theta) * math.cos(phi),
            cy + radius * math.cos(theta),
            cz - radius * math.sin(theta) * math.sin(phi),
        )

    tris = []
    for j in range(rings):
        for i in range(segments):
            a, b = point(i, j), point(i + 1, j)
            c, d = point(i + 1, j + 1), point(i, j + 1)
            top, bottom = (j < rings - 1, j > 0) if closed else (j > 0, j < rings - 1)
            if top:
                tris.append((a, d, c))  # d == c on the south pole: skipped there
            if bottom:
                tris.append((a, c, b))  # a == b on the north pole: skipped there
    return tris


def obj(name, material, tris, uvs=None, shared=False):
    """`shared`: the OBJ file lists each distinct vertex once (smaller, and watertight by
    construction) rather than three vertices a triangle (no uvs then)."""
    assert not (shared and uvs)
    return {"name": name, "material": material, "tris": tris, "uvs": uvs, "shared": shared}


def material(kd, ke=(0.0, 0.0, 0.0), map_kd=None, bsdf=None):
    """`bsdf`: None (diffuse, from the MTL) or a dict: "type" (cltrace's `bsdf` name:
    conductor, dielectric, thin-dielectric, plastic), "roughness" (cltrace's perceptual one,
    Mitsuba's alpha its square; below SMOOTH_ROUGHNESS the smooth Mitsuba plugin), and by
    type "eta", "k" (conductor, RGB), "ior" (dielectric, plastic); kd is then the plastic's
    diffuse reflectance (and unused by the others)."""
    return {"kd": tuple(kd), "ke": tuple(ke), "map_kd": map_kd, "bsdf": bsdf}


SMOOTH_ROUGHNESS = 0.03  # cltrace: below this roughness a lobe is a delta (bsdf.rs)


WHITE = material((0.75, 0.75, 0.75))
RED = material((0.63, 0.065, 0.05))
GREEN = material((0.14, 0.45, 0.091))


def light(radiance):
    # Albedo 0: an emitter reflects nothing, so its back face (where neither renderer emits)
    # is black in both, whatever light reaches it.
    return material((0.0, 0.0, 0.0), (radiance, radiance, radiance))


def cornell():
    """A diffuse Cornell box open towards +z, one white box inside, a square emitter just
    under the ceiling facing down (nothing above it but the ceiling, which it does not light
    directly)."""
    a, b, c, d = (-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)
    A, B, C, D = (-1, 2, 1), (1, 2, 1), (1, 2, -1), (-1, 2, -1)
    s, h = 0.3, 1.98
    return {
        "name": "cornell",
        "objects": [
            obj("floor", WHITE, quad(a, b, c, d)[0]),  # faces +y
            obj("ceiling", WHITE, quad(A, D, C, B)[0]),  # faces -y
            obj("back", WHITE, quad(d, c, C, D)[0]),  # faces +z
            obj("left", RED, quad(a, d, D, A)[0]),  # x = -1, faces +x
            obj("right", GREEN, quad(b, B, C, c)[0]),  # x = +1, faces -x
            obj("box", WHITE, box((0.05, 0.0, -0.6), (0.65, 0.6, 0.0))),
            obj("light", light(12.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 1.0, 3.6), "look_at": (0.0, 1.0, 0.0), "up": (0, 1, 0), "fov": 38.0},
        "max_bounces": 8,
    }


def quad_scene():
    """A floor lit by a square emitter above it facing down; the camera, above the emitter,
    sees its dark back."""
    s, h = 0.35, 1.0
    return {
        "name": "quad",
        "objects": [
            obj("floor", material((0.8, 0.6, 0.4)), quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1))[0]),
            obj("light", light(6.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 2.2, 2.4), "look_at": (0.0, 0.0, 0.0), "up": (0, 1, 0), "fov": 45.0},
        "max_bounces": 8,
    }


def sphere_scene():
    """A faceted diffuse UV sphere on a floor, lit by an emitter above."""
    s, h = 0.5, 2.0
    return {
        "name": "sphere",
        "objects": [
            obj("floor", WHITE, quad((-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2))[0]),
            obj("sphere", material((0.3, 0.5, 0.8)), uv_sphere((0.0, 0.5, 0.0), 0.5, 16, 10)),
            obj("light", light(8.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 0.45, 0.0), "up": (0, 1, 0), "fov": 40.0},
        "max_bounces": 8,
    }


def material_scene(name, sphere_material, doc, max_bounces=8):
    """The sphere scene's setup with a closed faceted sphere of another material."""
    s, h = 0.5, 2.0
    return {
        "name": name,
        "doc": doc,
        "objects": [
            obj("floor", WHITE, quad((-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2))[0]),
            obj("sphere", sphere_material, uv_sphere((0.0, 0.5, 0.0), 0.5, 16, 10, closed=True), shared=True),
            obj("light", light(8.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 0.45, 0.0), "up": (0, 1, 0), "fov": 40.0},
        "max_bounces": max_bounces,
    }


GOLD = {"eta": (0.143, 0.374, 1.442), "k": (3.983, 2.385, 1.603)}
SILVER = {"eta": (0.155, 0.117, 0.138), "k": (4.828, 3.122, 2.147)}
PLASTIC_ALBEDO = (0.2, 0.4, 0.8)


def gold_scene():
    m = material((1, 1, 1), bsdf={"type": "conductor", "roughness": 0.5, **GOLD})
    return material_scene("gold", m, "rough gold conductor (GGX, roughness 0.5: alpha 0.25)")


def mirror_scene():
    m = material((1, 1, 1), bsdf={"type": "conductor", "roughness": 0.0, **SILVER})
    return material_scene("mirror", m, "smooth silver conductor (a mirror)")


def glass_scene():
    m = material((1, 1, 1), bsdf={"type": "dielectric", "roughness": 0.0, "ior": 1.5})
    return material_scene("glass", m, "smooth dielectric, ior 1.5", max_bounces=24)


def rough_glass_scene():
    m = material((1, 1, 1), bsdf={"type": "dielectric", "roughness": 0.4, "ior": 1.5})
    return material_scene("rough-glass", m, "rough dielectric (GGX, roughness 0.4), ior 1.5", max_bounces=24)


def plastic_scene():
    m = material(PLASTIC_ALBEDO, bsdf={"type": "plastic", "roughness": 0.0, "ior": 1.5})
    return material_scene("plastic", m, "smooth plastic, ior 1.5")


def rough_plastic_scene():
    m = material(PLASTIC_ALBEDO, bsdf={"type": "plastic", "roughness": 0.4, "ior": 1.5})
    return material_scene("rough-plastic", m, "rough plastic (GGX, roughness 0.4), ior 1.5")


def rough_plastic_split_scene():
    m = material(PLASTIC_ALBEDO, bsdf={"type": "plastic", "roughness": 0.4, "ior": 1.5, "mitsuba": "split"})
    return material_scene(
        "rough-plastic-split", m,
        "rough plastic as cltrace models it: Mitsuba's roughplastic coating alone plus plastic's (smooth) base alone",
    )


def cornell_sphere_scene(name, sphere_material, doc, max_bounces=8):
    """The Cornell box with a closed faceted sphere of another material in place of the
    white box: a room, open only towards the camera, where most paths keep bouncing
    between the walls, the sphere and the light, rather than the material scenes' open
    floor, where most paths leave the scene early."""
    scene = cornell()
    objects = [o for o in scene["objects"] if o["name"] != "box"]
    sphere = uv_sphere((0.3, 0.45, -0.3), 0.45, 16, 10, closed=True)
    objects.insert(-1, obj("sphere", sphere_material, sphere, shared=True))
    return {**scene, "name": name, "doc": doc, "objects": objects, "max_bounces": max_bounces}


def cornell_gold_scene():
    m = material((1, 1, 1), bsdf={"type": "conductor", "roughness": 0.5, **GOLD})
    return cornell_sphere_scene("cornell-gold", m, "the Cornell box with a rough gold sphere (GGX, roughness 0.5)")


def cornell_glass_scene():
    m = material((1, 1, 1), bsdf={"type": "dielectric", "roughness": 0.0, "ior": 1.5})
    return cornell_sphere_scene("cornell-glass", m, "the Cornell box with a smooth glass sphere, ior 1.5",
                                max_bounces=24)


def pane_scene():
    """The diffuse sphere (closed) on the floor under the emitter, and in front of its left
    half a thin dielectric pane (ior 1.5), leaning back by 20 degrees, its front face towards
    the camera: the sphere and floor through it, the emitter's reflection in it, and its
    shadow (light through it, found by BSDF sampling only in both) on the floor."""
    s, h = 0.5, 2.0
    lean = math.radians(20.0)
    x0, x1, z, y1 = -0.9, 0.05, 0.9, 1.1
    top_z = z - y1 * math.tan(lean)
    pane = material((1, 1, 1), bsdf={"type": "thin-dielectric", "roughness": 0.0, "ior": 1.5})
    return {
        "name": "pane",
        "doc": "thin dielectric pane, ior 1.5",
        "objects": [
            obj("floor", WHITE, quad((-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2))[0]),
            obj("sphere", material((0.3, 0.5, 0.8)), uv_sphere((0.0, 0.5, 0.0), 0.5, 16, 10, closed=True), shared=True),
            obj("pane", pane, quad((x0, 0.0, z), (x1, 0.0, z), (x1, y1, top_z), (x0, y1, top_z))[0]),  # faces +z, up
            obj("light", light(8.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 0.45, 0.0), "up": (0, 1, 0), "fov": 40.0},
        "max_bounces": 8,
    }


CHECKER = 4  # squares per side of the textured scene's checkerboard
CHECKER_TEXELS = 2  # texels per square: magnified everywhere in the image, so that cltrace
# reads mip level 0 (bilinear, as Mitsuba, which has no mip maps) and not a blurrier level
CHECKER_COLOURS = ((220, 200, 60), (40, 70, 180))  # sRGB: square (i, j) has colour (i + j) % 2
MARKER_COLOUR = (230, 30, 30)  # square (0, 0) instead


def textured_scene():
    """A floor quad with a checkerboard texture (map_Kd): uv (0, 0) at the corner (-1, 0, 1),
    u along +x, v along -z, lit from above. Square (i, j) (i along u, j along v) has colour
    (i + j) % 2, but the corner square (0, 0) at uv (0, 0) is red, so that a flip of u or v
    or both in either renderer shows."""
    s, h = 0.4, 1.2
    uv = ((0, 0), (1, 0), (1, 1), (0, 1))
    tris, uvs = quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1), uv)
    return {
        "name": "textured",
        "objects": [
            obj("floor", material((1, 1, 1), map_kd="checker.png"), tris, uvs),
            obj("light", light(5.0), quad((-s, h, -s), (s, h, -s), (s, h, s), (-s, h, s))[0]),
        ],
        "camera": {"eye": (0.0, 1.0, 2.2), "look_at": (0.0, 0.0, 0.1), "up": (0, 1, 0), "fov": 50.0},
        "max_bounces": 8,
        "regions": "checker",
    }


# The lights other than emitting surfaces: an environment at infinity (a map or a constant
# colour) and point, spot and directional lights. A scene may name `environment` (a dict:
# "file" with "texels" the map's texels, or "color"; "intensity", "rotate" in degrees about
# +y) and `lights` (a list of dicts as cltrace's `[[light]]` tables: "type", "position",
# "intensity", "direction", "cutoff", "beam", "irradiance"), and then need no area emitter.

ENV_SIZE = (64, 32)  # the map's texels (width, height): u along the width, v down the height
ENV_ROTATE = 60.0  # degrees about +y (right-handed)
ENV_SUN_TOWARDS = (-0.7, 0.7, 0.1)  # the sun's world direction (from the scene towards it)
ENV_SUN_RADIANCE = (200.0, 185.0, 160.0)  # each of its 2 x 2 texels
ENV_UPSAMPLE = 8  # Mitsuba's copy of the map: each texel 8 x 8 (README: why, and why exact)


def rotate_y(d, degrees):
    """`d` rotated about +y by `degrees`, right-handed (Mitsuba's rotate([0, 1, 0], angle))."""
    a = math.radians(degrees)
    x, y, z = d
    return (x * math.cos(a) + z * math.sin(a), y, -x * math.sin(a) + z * math.cos(a))


def env_uv(d):
    """Mitsuba's envmap coordinates of a direction in the map's frame: u = atan2(x, -z) / 2 pi
    wrapped to [0, 1), v = acos(y) / pi (v = 0 at +y, the image's top row)."""
    n = math.sqrt(sum(c * c for c in d))
    x, y, z = (c / n for c in d)
    return (math.atan2(x, -z) / (2.0 * math.pi)) % 1.0, math.acos(max(-1.0, min(1.0, y))) / math.pi


def env_texels():
    """The environment map (H x W x 3, float32, row 0 the top: v = 0, +y): a smooth sky, its
    texel (i, j) the value at its centre u = (i + 0.5) / W, v = (j + 0.5) / H (the map's own
    frame, before `rotate`): from white-yellow at the horizon to blue at the zenith, a brown
    ground below the horizon darkening to the nadir, all brighter by up to 30% towards u = 0
    (the map's -z) and darker opposite, so that a rotation shows without the sun too; and a
    sun of 2 x 2 texels of ENV_SUN_RADIANCE, its centre the texel corner nearest to
    ENV_SUN_TOWARDS turned back by ENV_ROTATE (so that the rotated map puts it there)."""
    w, h = ENV_SIZE
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    y = np.cos(math.pi * v)[:, None, None]
    phi = 2.0 * math.pi * u[None, :, None]
    horizon, zenith = np.array((0.9, 0.85, 0.7)), np.array((0.2, 0.4, 0.9))
    ground, nadir = np.array((0.3, 0.25, 0.2)), np.array((0.08, 0.07, 0.06))
    up, down = np.sqrt(np.clip(y, 0.0, 1.0)), np.sqrt(np.clip(-y, 0.0, 1.0))
    sky = np.where(y >= 0.0, horizon * (1.0 - up) + zenith * up, ground * (1.0 - down) + nadir * down)
    sky = sky * (1.0 + 0.3 * np.cos(phi))
    su, sv = env_uv(rotate_y(ENV_SUN_TOWARDS, -ENV_ROTATE))
    col, row = int(round(su * w)) - 1, int(round(sv * h)) - 1
    for j in (row, row + 1):
        for i in (col, col + 1):
            sky[j, i % w] = ENV_SUN_RADIANCE
    return sky.astype(np.float32)


def env_upsampled(tex, k=ENV_UPSAMPLE):
    """Mitsuba's copy of a nearest-looked-up map: Mitsuba's envmap is bilinear only, its
    column i at u = (i + 0.5) / W, its row j at v = j / (H - 1). Each texel becomes k
    columns, and the rows are k H + 1, row r at v = r / (k H): the nearest texel's value
    there, or on a texel edge (r a multiple of k) the mean of the two texels it parts. The
    bilinear function of that equals the nearest function but in bands of 1/k texel along
    the texel edges, where it is a ramp antisymmetric about the edge: integrals over the
    sphere (the light reaching anything) agree exactly but for the sin(theta) weight across a
    band, a second-order term (README)."""
    h, w = tex.shape[:2]
    cols = np.repeat(tex, k, axis=1)
    rows = []
    for r in range(k * h + 1):
        if r % k == 0 and 0 < r < k * h:
            rows.append((cols[r // k - 1] + cols[r // k]) / 2.0)
        else:
            rows.append(cols[min(r // k, h - 1)])
    return np.ascontiguousarray(np.stack(rows), dtype=np.float32)


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def lights_floor():
    return obj("floor", WHITE, quad((-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2))[0])


def lights_sphere(center=(0.0, 0.5, 0.0), radius=0.5, m=None):
    return obj("sphere", m or material((0.3, 0.5, 0.8)), uv_sphere(center, radius, 16, 10, closed=True), shared=True)


SPHERE_CAMERA = {"eye": (0.0, 1.3, 2.6), "look_at": (0.0, 0.45, 0.0), "up": (0, 1, 0), "fov": 40.0}


def env_scene():
    """A diffuse sphere (left) and a rough gold one (right) on the floor under the
    environment map (env_texels), rotated by ENV_ROTATE: no emitting surface. The camera,
    lower than the sphere scene's, sees the map over the floor's far edge (the top of the
    image: below and above the horizon); the sun, to the left and up, is not in view but
    casts the spheres' soft shadows to the right."""
    gold = material((1, 1, 1), bsdf={"type": "conductor", "roughness": 0.4, **GOLD})
    return {
        "name": "env",
        "doc": "an environment map (nearest texels, rotated 60 degrees) with a sun",
        "objects": [
            lights_floor(),
            obj("diffuse", material((0.3, 0.5, 0.8)), uv_sphere((-0.55, 0.4, 0.0), 0.4, 16, 10, closed=True),
                shared=True),
            obj("gold", gold, uv_sphere((0.55, 0.4, 0.0), 0.4, 16, 10, closed=True), shared=True),
        ],
        "environment": {"file": "env.exr", "texels": env_texels, "intensity": 1.25, "rotate": ENV_ROTATE},
        "camera": {"eye": (0.0, 0.9, 3.2), "look_at": (0.0, 0.45, 0.0), "up": (0, 1, 0), "fov": 40.0},
        "max_bounces": 8,
    }


def background_scene():
    """The diffuse sphere on the floor under a constant environment (a background that
    lights the scene, furnace-like): seen directly over the floor's far edge it is exactly
    its colour times its intensity in both."""
    return {
        "name": "background",
        "doc": "a constant environment colour",
        "objects": [lights_floor(), lights_sphere()],
        "environment": {"color": (0.5, 0.6, 0.8), "intensity": 1.5},
        "camera": SPHERE_CAMERA,
        "max_bounces": 8,
    }


def point_scene():
    """The diffuse sphere on the floor lit by a point light up to the left: its hard shadow
    on the floor to the right, partly behind it."""
    return {
        "name": "point",
        "doc": "a point light",
        "objects": [lights_floor(), lights_sphere()],
        "lights": [{"type": "point", "position": (-0.7, 1.4, 0.3), "intensity": (4.0, 3.6, 3.0)}],
        "camera": SPHERE_CAMERA,
        "max_bounces": 8,
        "regions": "light",
    }


def spot_scene():
    """The diffuse sphere on the floor and a spot light up to the left and in front, aimed
    at the floor in front of the sphere at an angle (28 degrees off the vertical): cutoff 25
    and beam 15 degrees, so that the falloff band (linear in angle between, as Mitsuba's) is
    a ring several pixels wide around the beam's ellipse, all in view; the sphere, at the
    cone's edge, is lit in part and casts a shadow to the right."""
    position, target = (-0.8, 1.8, 1.2), (0.0, 0.0, 0.7)
    return {
        "name": "spot",
        "doc": "a spot light (cutoff 25, beam 15 degrees)",
        "objects": [lights_floor(), lights_sphere()],
        "lights": [{"type": "spot", "position": position, "intensity": (12.0, 12.0, 10.0),
                    "direction": unit([t - p for t, p in zip(target, position)]), "cutoff": 25.0, "beam": 15.0}],
        "camera": SPHERE_CAMERA,
        "max_bounces": 8,
        "regions": "light",
    }


def directional_scene():
    """The diffuse sphere on the floor lit by a directional light travelling down, to the
    left and away from the camera: the sphere's hard shadow on the floor behind it to the
    left."""
    return {
        "name": "directional",
        "doc": "a directional light",
        "objects": [lights_floor(), lights_sphere()],
        "lights": [{"type": "directional", "direction": unit((-0.5, -0.7, -0.5)), "irradiance": (2.0, 1.8, 1.5)}],
        "camera": SPHERE_CAMERA,
        "max_bounces": 8,
        "regions": "light",
    }


SCENES = {
    s()["name"]: s
    for s in (
        cornell,
        quad_scene,
        sphere_scene,
        textured_scene,
        gold_scene,
        mirror_scene,
        glass_scene,
        rough_glass_scene,
        plastic_scene,
        rough_plastic_scene,
        rough_plastic_split_scene,
        pane_scene,
        cornell_gold_scene,
        cornell_glass_scene,
        env_scene,
        background_scene,
        point_scene,
        spot_scene,
        directional_scene,
    )
}


# ---------------------------------------------------------------------------------------------
# Writing the inputs: OBJ + MTL (+ PNG) and the cltrace scene file.


def fmt(x):
    return repr(float(x))


def fmt_obj(x):
    """A coordinate in an OBJ file: 7 significant digits (both renderers read the same file)."""
    return f"{float(x):.7g}"


def write_png(path, pixels):
    """An 8-bit PNG, grey (H x W) or RGB (H x W x 3), unfiltered rows."""
    pixels = np.ascontiguousarray(pixels, dtype=np.uint8)
    h, w = pixels.shape[:2]
    colour = 2 if pixels.ndim == 3 else 0
    raw = b"".join(b"\x00" + pixels[y].tobytes() for y in range(h))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def write_exr(path, rgb):
    """A float32 RGB OpenEXR file (H x W x 3, row 0 the top), uncompressed scanlines: the
    environment map, written with numpy alone (Mitsuba reads it back for its copy)."""
    rgb = np.ascontiguousarray(rgb, dtype="<f4")
    h, w = rgb.shape[:2]

    def attr(name, kind, value):
        return name.encode() + b"\x00" + kind.encode() + b"\x00" + struct.pack("<i", len(value)) + value

    channels = b"".join(c.encode() + b"\x00" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR") + b"\x00"
    window = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = b"".join([
        b"\x76\x2f\x31\x01" + struct.pack("<i", 2),
        attr("channels", "chlist", channels),
        attr("compression", "compression", b"\x00"),
        attr("dataWindow", "box2i", window),
        attr("displayWindow", "box2i", window),
        attr("lineOrder", "lineOrder", b"\x00"),
        attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)),
        attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)),
        attr("screenWindowWidth", "float", struct.pack("<f", 1.0)),
        b"\x00",
    ])
    line = 8 + 3 * 4 * w  # y, size, then the channels' rows in the header's order (B, G, R)
    start = len(header) + 8 * h
    with open(path, "wb") as f:
        f.write(header)
        f.write(b"".join(struct.pack("<Q", start + y * line) for y in range(h)))
        for y in range(h):
            f.write(struct.pack("<ii", y, 3 * 4 * w))
            for c in (2, 1, 0):
                f.write(rgb[y, :, c].tobytes())


def read_png_grey(path):
    """The grey 8-bit PNGs write_png writes (one IDAT or several, rows of any filter)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour == 0, f"{path}: not an 8-bit grey PNG"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    out = np.zeros((h, w), np.uint8)
    prev = np.zeros(w, np.int32)
    for y in range(h):
        ftype, row = raw[y * (w + 1)], np.frombuffer(raw, np.uint8, w, y * (w + 1) + 1).astype(np.int32)
        cur = np.zeros(w, np.int32)
        for x in range(w):
            left = cur[x - 1] if x else 0
            up, ul = prev[x], (prev[x - 1] if x else 0)
            if ftype == 0:
                p = 0
            elif ftype == 1:
                p = left
            elif ftype == 2:
                p = up
            elif ftype == 3:
                p = (left + up) // 2
            else:
                pa, pb, pc = abs(up - ul), abs(left - ul), abs(left + up - 2 * ul)
                p = left if pa <= pb and pa <= pc else (up if pb <= pc else ul)
            cur[x] = (row[x] + p) & 255
        out[y], prev = cur, cur
    return out


def checker_texture():
    n = CHECKER * CHECKER_TEXELS
    img = np.zeros((n, n, 3), np.uint8)
    for row in range(n):
        j = CHECKER - 1 - row // CHECKER_TEXELS  # image row 0 is the top: v = 1 (OBJ convention)
        for col in range(n):
            i = col // CHECKER_TEXELS
            img[row, col] = CHECKER_COLOURS[(i + j) % 2]
    # The marker: square (0, 0), at uv (0, 0) (the image's bottom left), is red.
    img[n - CHECKER_TEXELS :, :CHECKER_TEXELS] = MARKER_COLOUR
    return img


def write_inputs(scene, out, width, height, spp, seed=0):
    """Writes the scene's OBJ, MTL, texture and scene.toml into `out`; returns the paths of
    the OBJ files, object by object."""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "scene.mtl"), "w") as f:
        f.write(f"# {scene['name']}: written by scripts/mitsuba/compare.py\n")
        for o in scene["objects"]:
            m = o["material"]
            f.write(f"\nnewmtl {o['name']}\n")
            f.write("Kd " + " ".join(fmt(x) for x in m["kd"]) + "\n")
            f.write("Ke " + " ".join(fmt(x) for x in m["ke"]) + "\n")
            if m["map_kd"]:
                f.write(f"map_Kd {m['map_kd']}\n")
                write_png(os.path.join(out, m["map_kd"]), checker_texture())
    paths = []
    for o in scene["objects"]:
        path = os.path.join(out, o["name"] + ".obj")
        with open(path, "w") as f:
            f.write(f"# {scene['name']}/{o['name']}: written by scripts/mitsuba/compare.py\n")
            f.write("mtllib scene.mtl\n")
            f.write(f"o {o['name']}\nusemtl {o['name']}\n")
            if o["shared"]:
                index = {}
                for t in o["tris"]:
                    for p in t:
                        v = " ".join(fmt_obj(x) for x in p)
                        if v not in index:
                            index[v] = len(index) + 1
                            f.write(f"v {v}\n")
                for t in o["tris"]:
                    f.write("f " + " ".join(str(index[" ".join(fmt_obj(x) for x in p)]) for p in t) + "\n")
                paths.append(path)
                continue
            for t in o["tris"]:
                for p in t:
                    f.write("v " + " ".join(fmt_obj(x) for x in p) + "\n")
            if o["uvs"]:
                for t in o["uvs"]:
                    for uv in t:
                        f.write("vt " + " ".join(fmt_obj(x) for x in uv) + "\n")
            for k in range(len(o["tris"])):
                i = 3 * k + 1
                if o["uvs"]:
                    f.write(f"f {i}/{i} {i + 1}/{i + 1} {i + 2}/{i + 2}\n")
                else:
                    f.write(f"f {i} {i + 1} {i + 2}\n")
        paths.append(path)
    env = scene.get("environment")
    if env and "file" in env:
        write_exr(os.path.join(out, env["file"]), env["texels"]())
    cam = scene["camera"]
    vec = lambda v: "[" + ", ".join(fmt(x) for x in v) + "]"  # noqa: E731
    with open(os.path.join(out, "scene.toml"), "w") as f:
        f.write(f"# {scene['name']}: written by scripts/mitsuba/compare.py from the same description\n")
        f.write("# as the Mitsuba scene of its references (scripts/mitsuba/README.md).\n")
        for o in scene["objects"]:
            f.write(f'\n[[mesh]]\nfile = "{o["name"]}.obj"\n')
            if o["material"]["bsdf"]:
                f.write(f"material = {toml_material(o['material'])}\n")
        if env:
            f.write("\n[environment]\n")
            f.write(f'file = "{env["file"]}"\n' if "file" in env else f"color = {vec(env['color'])}\n")
            f.write(f"intensity = {fmt(env.get('intensity', 1.0))}\nrotate = {fmt(env.get('rotate', 0.0))}\n")
        for light in scene.get("lights", []):
            f.write(f'\n[[light]]\ntype = "{light["type"]}"\n')
            for key in ("position", "intensity", "direction", "cutoff", "beam", "irradiance"):
                if key in light:
                    x = light[key]
                    f.write(f"{key} = {vec(x) if isinstance(x, (tuple, list)) else fmt(x)}\n")
        f.write("\n[camera]\n")
        f.write(f"eye = {vec(cam['eye'])}\nlook_at = {vec(cam['look_at'])}\nup = {vec(cam['up'])}\n")
        f.write(f"fov = {fmt(cam['fov'])}\nwidth = {width}\nheight = {height}\n")
        f.write('\n[render]\nshade = "path"\n')
        f.write(f"spp = {spp}\nseed = {seed}\nmax_bounces = {scene['max_bounces']}\n")
        f.write("crease_angle = 0.0\ntwo_sided_lights = false\n")
    return paths


def toml_material(m):
    """A `[[mesh]]` table's `material` (overriding the MTL) of a material with a bsdf."""
    b = m["bsdf"]
    vec = lambda v: "[" + ", ".join(fmt(x) for x in v) + "]"  # noqa: E731
    keys = [f"albedo = {vec(m['kd'])}", f'bsdf = "{b["type"]}"', f"roughness = {fmt(b['roughness'])}"]
    if "ior" in b:
        keys.append(f"ior = {fmt(b['ior'])}")
    if "eta" in b:
        keys += [f"eta = {vec(b['eta'])}", f"k = {vec(b['k'])}"]
    return "{ " + ", ".join(keys) + " }"


def mitsuba_bsdf(m):
    """The Mitsuba bsdf of a material with a bsdf (cltrace's model, bsdf.rs)."""
    b = m["bsdf"]
    rgb = lambda v: {"type": "rgb", "value": list(v)}  # noqa: E731
    smooth = b["roughness"] < SMOOTH_ROUGHNESS
    rough = {"distribution": "ggx", "alpha": b["roughness"] ** 2, "sample_visible": True}
    kind = b["type"]
    if kind == "conductor":
        d = {"type": "conductor", "eta": rgb(b["eta"]), "k": rgb(b["k"])}
        return d if smooth else {**d, "type": "roughconductor", **rough}
    if kind == "dielectric":
        d = {"type": "dielectric", "int_ior": b["ior"], "ext_ior": 1.0}
        return d if smooth else {**d, "type": "roughdielectric", **rough}
    if kind == "thin-dielectric":
        return {"type": "thindielectric", "int_ior": b["ior"], "ext_ior": 1.0}
    if kind == "plastic" and b.get("mitsuba") == "split" and not smooth:
        # cltrace's rough plastic: roughplastic's coating (F D G / (4 cos_o), its base off)
        # plus plastic's base (smooth Fresnel terms, its coating off), summed as a blend of
        # weight 0.8 of each scaled by 1 / its weight (reflectances must stay in [0, 1]).
        w = 0.8
        coat = {"type": "roughplastic", **rough, "diffuse_reflectance": rgb((0, 0, 0)),
                "specular_reflectance": 1.0 / (1.0 - w), "int_ior": b["ior"], "ext_ior": 1.0, "nonlinear": False}
        base = {"type": "plastic", "diffuse_reflectance": rgb([x / w for x in m["kd"]]), "specular_reflectance": 0.0,
                "int_ior": b["ior"], "ext_ior": 1.0, "nonlinear": False}
        assert max(m["kd"]) <= w
        return {"type": "blendbsdf", "weight": w, "bsdf_0": coat, "bsdf_1": base}
    if kind == "plastic":
        d = {"type": "plastic", "diffuse_reflectance": rgb(m["kd"]), "int_ior": b["ior"], "ext_ior": 1.0,
             "nonlinear": False}
        return d if smooth else {**d, "type": "roughplastic", **rough}
    raise ValueError(f"no Mitsuba bsdf for {kind!r}")


# ---------------------------------------------------------------------------------------------
# Mitsuba.


def mitsuba(variant=MITSUBA_VARIANT):
    import mitsuba as mi

    mi.set_variant(variant)
    return mi


def mitsuba_scene(mi, scene, out, width, height, spp, max_bounces, rr_depth=10000):
    cam = scene["camera"]
    d = {
        "type": "scene",
        "integrator": {
            "type": "path",
            # cltrace's bounce 0 is the camera ray's hit with its light sample (NEE); Mitsuba's
            # depth 1 is the emitters seen directly, depth 2 adds that first NEE.
            "max_depth": max_bounces + 2,
            # None by default (the references' noise only); `speed` starts it where cltrace does.
            "rr_depth": rr_depth,
            "hide_emitters": False,
        },
        "sensor": {
            "type": "perspective",
            "fov": cam["fov"],
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=list(cam["eye"]), target=list(cam["look_at"]), up=list(cam["up"])
            ),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
            "sampler": {"type": "independent", "sample_count": spp},
        },
    }
    for o in scene["objects"]:
        m = o["material"]
        if m["map_kd"]:
            reflectance = {
                "type": "bitmap",
                "filename": os.path.join(out, m["map_kd"]),
                "raw": False,  # sRGB, decoded to linear, as cltrace decodes a base colour
                "filter_type": "bilinear",
                "wrap_mode": "repeat",
            }
        else:
            reflectance = {"type": "rgb", "value": list(m["kd"])}
        shape = {
            "type": "obj",
            "filename": os.path.join(out, o["name"] + ".obj"),
            "face_normals": True,
        }
        if m["bsdf"]:
            # Not wrapped in `twosided`: the scenes' conductors and plastics are closed
            # spheres (only front faces seen), and dielectrics are one-sided in both.
            shape["bsdf"] = mitsuba_bsdf(m)
        elif any(m["ke"]):
            # One-sided, as cltrace's emitters (front face only); albedo 0 in both.
            shape["bsdf"] = {"type": "diffuse", "reflectance": reflectance}
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(m["ke"])}}
        else:
            # cltrace shades a back face like the front.
            shape["bsdf"] = {"type": "twosided", "material": {"type": "diffuse", "reflectance": reflectance}}
        d[o["name"]] = shape
    d.update(mitsuba_lights(mi, scene, out))
    # optimize=False: no merging of the objects of one bsdf into one shape (the region map
    # tells them apart by shape).
    return mi.load_dict(d, optimize=False)


def mitsuba_lights(mi, scene, out):
    """The Mitsuba emitters of a scene's environment and lights (README: the correspondence)."""
    rgb = lambda v: {"type": "rgb", "value": list(v) if isinstance(v, (tuple, list)) else [v] * 3}  # noqa: E731
    d = {}
    env = scene.get("environment")
    if env and "file" in env:
        # Mitsuba's envmap has no nearest lookup (filter_type is not one of its parameters
        # in 3.9.1: load_dict rejects it as unreferenced): it gets the file's texels (read
        # back, so exactly what cltrace reads) upsampled so that its bilinear function is
        # the nearest one but in thin bands that cancel (env_upsampled).
        tex = np.array(mi.Bitmap(os.path.join(out, env["file"])).convert(
            mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False), dtype=np.float32)
        d["environment"] = {
            "type": "envmap",
            "bitmap": mi.Bitmap(env_upsampled(tex), mi.Bitmap.PixelFormat.RGB),
            "scale": env.get("intensity", 1.0),
            "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], env.get("rotate", 0.0)),
        }
    elif env:
        # `constant` has no scale: the intensity multiplies its radiance.
        d["environment"] = {"type": "constant", "radiance": rgb([env.get("intensity", 1.0) * c for c in env["color"]])}
    for n, light in enumerate(scene.get("lights", [])):
        kind = light["type"]
        if kind == "point":
            e = {"type": "point", "position": list(light["position"]), "intensity": rgb(light["intensity"])}
        elif kind == "spot":
            cutoff = light.get("cutoff", 20.0)
            p = light["position"]
            e = {
                "type": "spot",
                "intensity": rgb(light["intensity"]),
                "cutoff_angle": cutoff,
                "beam_width": light.get("beam", 0.75 * cutoff),
                # The spot's axis is its local +z: look_at turns it towards the target.
                "to_world": mi.ScalarTransform4f().look_at(
                    origin=list(p), target=[a + b for a, b in zip(p, light["direction"])],
                    up=[0, 1, 0] if abs(unit(light["direction"])[1]) < 0.9 else [1, 0, 0],
                ),
            }
        elif kind == "directional":
            e = {"type": "directional", "direction": list(light["direction"]), "irradiance": rgb(light["irradiance"])}
        else:
            raise ValueError(f"no Mitsuba emitter for a {kind!r} light")
        d[f"light_{n}"] = e
    return d


def region_map(mi, loaded, scene, width, height):
    """Regions: each object's pixels in each of TILES x TILES parts of the image (the textured
    scene: each checker colour instead of each object), a pixel counted only where all of its
    SUBSAMPLES^2 probe rays (a grid reaching the pixel's edges) see the same thing; small
    regions are dropped. Returns the map (H x W, UNCHECKED outside) and the regions' names."""
    sensor = loaded.sensors()[0]
    names = [o["name"] for o in scene["objects"]]
    checker = scene.get("regions") == "checker"
    by_light = scene.get("regions") == "light"
    kinds = names + ["floor/colour 0", "floor/colour 1", "floor/marker", "environment"]
    kinds += [f"floor/{c}" for c in LIGHT_CLASSES]
    k = SUBSAMPLES
    offsets = [0.02 + 0.96 * i / (k - 1) for i in range(k)]
    label = np.full((height, width), -1, np.int64)
    for y in range(height):
        for x in range(width):
            seen = set()
            for oy in offsets:
                for ox in offsets:
                    ray, _ = sensor.sample_ray(
                        0.0, 0.5, mi.ScalarPoint2f((x + ox) / width, (y + oy) / height), mi.ScalarPoint2f(0.5, 0.5)
                    )
                    si = loaded.ray_intersect(ray)
                    if not si.is_valid():
                        # A miss sees the environment, if any (the same function in both).
                        seen.add(kinds.index("environment") if scene.get("environment") else None)
                        continue
                    what = names.index(si.shape.id())
                    if by_light and names[what] == "floor":
                        what = kinds.index("floor/" + light_class(mi, loaded, si, scene["lights"][0]))
                    if checker and scene["objects"][what]["material"]["map_kd"]:
                        # The floor's square from the hit's position (uv (0,0) at x=-1, z=+1).
                        u, v = (si.p[0] + 1.0) / 2.0, (1.0 - si.p[2]) / 2.0
                        i = min(int(u * CHECKER), CHECKER - 1)
                        j = min(int(v * CHECKER), CHECKER - 1)
                        what = len(names) + (2 if i == 0 and j == 0 else (i + j) % 2)
                    seen.add(what)
            if len(seen) == 1 and None not in seen:
                label[y, x] = seen.pop()
    regions, out = [], np.full((height, width), UNCHECKED, np.uint8)
    least = max(4, width * height // 256)
    rows = ["top", "bottom"] if TILES == 2 else [f"row {r}" for r in range(TILES)]
    cols = ["left", "right"] if TILES == 2 else [f"column {c}" for c in range(TILES)]
    for what, kind in enumerate(kinds):
        for ty in range(TILES):
            for tx in range(TILES):
                mask = np.zeros_like(label, bool)
                ys, xs = slice(ty * height // TILES, (ty + 1) * height // TILES), slice(
                    tx * width // TILES, (tx + 1) * width // TILES
                )
                mask[ys, xs] = label[ys, xs] == what
                n = int(mask.sum())
                if n < least:
                    continue
                assert len(regions) < UNCHECKED
                out[mask] = len(regions)
                regions.append({"index": len(regions), "name": f"{kind} {rows[ty]}-{cols[tx]}", "pixels": n})
    return out, regions


LIGHT_CLASSES = ("lit", "shadow", "beam", "falloff", "outside")


def light_class(mi, loaded, si, light):
    """What a point of the floor gets of a light: a spot's "outside" (beyond its cutoff),
    "shadow" (the light occluded), a spot's "beam" (full) or "falloff" (between beam and
    cutoff), a point or directional light's "lit"."""
    p = np.array(si.p, dtype=np.float64)
    if light["type"] == "directional":
        ray = si.spawn_ray(mi.Vector3f(*[-c for c in unit(light["direction"])]))
    else:
        ray = si.spawn_ray_to(mi.Point3f(*light["position"]))
    angle = None
    if light["type"] == "spot":
        to_p = unit(p - np.array(light["position"]))
        cos = float(np.dot(to_p, unit(light["direction"])))
        angle = math.degrees(math.acos(max(-1.0, min(1.0, cos))))
        if angle >= light.get("cutoff", 20.0):
            return "outside"
    if loaded.ray_test(ray):
        return "shadow"
    if angle is None:
        return "lit"
    return "beam" if angle <= light.get("beam", 0.75 * light.get("cutoff", 20.0)) else "falloff"


def write_exr_half(mi, path, rgb):
    bmp = mi.Bitmap(np.ascontiguousarray(rgb, dtype=np.float32), mi.Bitmap.PixelFormat.RGB)
    bmp = bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float16, False)
    bmp.write(path)


def read_exr(path):
    """Linear RGB (H x W x 3, float64) of an EXR file, through Mitsuba's Bitmap."""
    mi = mitsuba()
    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    return np.array(bmp, dtype=np.float64)


def parse_size(text):
    w, h = text.lower().split("x")
    return int(w), int(h)


def selected(names):
    if not names:
        return list(SCENES)
    picked = names.split(",")
    for n in picked:
        if n not in SCENES:
            sys.exit(f"compare.py: no scene {n!r} (the scenes: {', '.join(SCENES)})")
    return picked


def cmd_scenes(args):
    w, h = parse_size(args.size)
    for name in selected(args.scenes):
        scene = SCENES[name]()
        write_inputs(scene, os.path.join(args.out, name), w, h, args.spp)
        print(f"{name}: {os.path.join(args.out, name, 'scene.toml')}")


def cmd_reference(args):
    mi = mitsuba()
    w, h = parse_size(args.size)
    for name in selected(args.scenes):
        scene = SCENES[name]()
        if args.max_bounces is not None:
            scene["max_bounces"] = args.max_bounces
        out = os.path.join(args.out, name)
        write_inputs(scene, out, w, h, args.check_spp)
        start = time.time()
        loaded = mitsuba_scene(mi, scene, out, w, h, args.spp, scene["max_bounces"])
        for seed in (0, 1):
            img = np.array(mi.render(loaded, spp=args.spp, seed=seed), dtype=np.float32)
            write_exr_half(mi, os.path.join(out, f"mitsuba_{seed}.exr"), img)
        rendered = time.time() - start
        regions_png, regions = region_map(mi, loaded, scene, w, h)
        write_png(os.path.join(out, "regions.png"), regions_png)
        info = {
            "scene": name,
            "written_by": "scripts/mitsuba/compare.py reference",
            "mitsuba": mi.__version__,
            "variant": MITSUBA_VARIANT,
            "size": [w, h],
            "spp_per_half": args.spp,
            "halves": {"mitsuba_0.exr": 0, "mitsuba_1.exr": 1},
            "max_bounces": scene["max_bounces"],
            "mitsuba_max_depth": scene["max_bounces"] + 2,
            "cltrace_scene": "scene.toml",
            "regions_png": "regions.png: 8-bit grey, a pixel's region index, 255 = not checked",
            "regions": regions,
            "tolerance": {
                "sigmas": SIGMAS,
                "bias": BIAS,
                "rule": "per region and channel: |c - m| <= sigmas * sqrt(sc^2 + sm^2) + bias * m, "
                "c and m the region's mean of both halves, s^2 = sum over the region's pixels of "
                "((half0 - half1) / 2)^2 / pixels^2",
            },
        }
        with open(os.path.join(out, "scene.json"), "w") as f:
            json.dump(info, f, indent=1)
            f.write("\n")
        print(f"{name}: {w}x{h}, 2 x {args.spp} spp in {rendered:.1f} s, {len(regions)} regions -> {out}")


def region_stats(a, b, mask):
    """Mean of both halves over the region, per channel, and its standard deviation: the
    pixels are independent, and ((a - b) / 2)^2 is an unbiased estimate of the variance of a
    pixel's mean (a + b) / 2 when a and b are independent estimates with one distribution."""
    n = mask.sum()
    mean = ((a[mask] + b[mask]) / 2).sum(axis=0) / n
    var = (((a[mask] - b[mask]) / 2) ** 2).sum(axis=0) / n**2
    return mean, np.sqrt(var)


def compare(c0, c1, m0, m1, regions_png, regions):
    """Rows (region, channel, c, m, diff, allowance, pass) of one scene."""
    rows = []
    for r in regions:
        mask = regions_png == r["index"]
        c, sc = region_stats(c0, c1, mask)
        m, sm = region_stats(m0, m1, mask)
        for ch, cname in enumerate("RGB"):
            allow = SIGMAS * math.hypot(sc[ch], sm[ch]) + BIAS * m[ch]
            diff = c[ch] - m[ch]
            rows.append((r["name"], cname, c[ch], m[ch], diff, allow, abs(diff) <= allow))
    return rows


def cmd_check(args):
    refs = args.refs
    dirs = [refs] if os.path.exists(os.path.join(refs, "scene.json")) else [
        os.path.join(refs, d) for d in sorted(os.listdir(refs)) if os.path.exists(os.path.join(refs, d, "scene.json"))
    ]
    if args.scenes:
        dirs = [d for d in dirs if os.path.basename(d) in args.scenes.split(",")]
    if not dirs:
        sys.exit(f"compare.py: no references (scene.json) in {refs}")
    half = max(1, args.spp // 2)
    failed = 0
    print(f"{'scene':<9} {'region':<28} ch {'cltrace':>9} {'mitsuba':>9} {'diff %':>8} {'allow %':>8}  pass")
    with tempfile.TemporaryDirectory() as tmp:
        for d in dirs:
            info = json.load(open(os.path.join(d, "scene.json")))
            w, h = info["size"]
            cl = []
            start = time.time()
            for seed in (0, 1):
                path = os.path.join(tmp, f"{info['scene']}_{seed}.exr")
                cmd = [args.cltrace, "render", os.path.join(d, info["cltrace_scene"]), "--shade", "path",
                       "--spp", str(half), "--seed", str(seed), "--max-bounces", str(info["max_bounces"]),
                       "--width", str(w), "--height", str(h), "-o", path, "-q"]
                if subprocess.run(cmd).returncode != 0:
                    sys.exit(f"compare.py: cltrace failed on {info['scene']}: {' '.join(cmd)}")
                cl.append(read_exr(path))
            took = time.time() - start
            m0, m1 = (read_exr(os.path.join(d, f)) for f in ("mitsuba_0.exr", "mitsuba_1.exr"))
            rows = compare(cl[0], cl[1], m0, m1, read_png_grey(os.path.join(d, "regions.png")), info["regions"])
            for name, ch, c, m, diff, allow, ok in rows:
                pct = lambda x: f"{100 * x / m:8.2f}" if m > 0 else f"{'-':>8}"  # noqa: E731
                print(f"{info['scene']:<9} {name:<28} {ch}  {c:9.5f} {m:9.5f} {pct(diff)} {pct(allow)}  "
                      f"{'yes' if ok else 'NO'}")
                failed += not ok
            print(f"# {info['scene']}: cltrace 2 x {half} spp in {took:.1f} s, Mitsuba 2 x {info['spp_per_half']} spp")
    if failed:
        print(f"{failed} region channels disagree beyond the tolerance")
        sys.exit(1)
    print("every region agrees within the tolerance")


# cltrace's Russian roulette starts after the BSDF sample of bounce ROULETTE_AFTER = 3
# (src/render/integrator.rs); Mitsuba's after the BSDF sample that makes its depth rr_depth,
# depth 1 being the camera ray's hit: the same vertex is rr_depth 4.
RR_DEPTH_OF_CLTRACE = 4


def cmd_speed(args):
    """Samples per second of both renderers on the same scenes at equal settings: image
    size, spp, path length, Russian roulette from the same vertex, box filter, one-sided
    emitters. Mitsuba's time is mi.render's; cltrace's the samples stage of `render --json`
    (its `sampling_ms`). Each repetition renders the scene once with every renderer in
    turn, so that a machine whose speed drifts (a shared host's does) moves them alike; the
    first is a warm-up (Mitsuba's JIT compile, cltrace's kernel compile). Prints medians of
    --repetitions, and each repetition's ratio to Mitsuba's time."""
    mi = mitsuba(args.variant)
    import drjit as dr

    w, h = parse_size(args.size)
    devices = args.devices.split(",")
    rows = []
    for name in selected(args.scenes):
        scene = SCENES[name]()
        scene["max_bounces"] = args.max_bounces
        out = os.path.join(args.out, name)
        write_inputs(scene, out, w, h, args.spp)
        loaded = mitsuba_scene(mi, scene, out, w, h, args.spp, args.max_bounces, RR_DEPTH_OF_CLTRACE)
        mitsuba_times = []
        cltrace_times = {device: [] for device in devices}
        labels = {}
        for k in range(args.repetitions + 1):
            start = time.perf_counter()
            img = mi.render(loaded, spp=args.spp, seed=k)
            dr.eval(img)
            np.array(img)
            if k > 0:
                mitsuba_times.append(time.perf_counter() - start)
            for device in devices:
                summary = os.path.join(out, "run.json")
                cmd = [args.cltrace, "render", os.path.join(out, "scene.toml"), "-q", "--device", device,
                       "--max-bounces", str(args.max_bounces), "-o", os.path.join(out, "speed.exr"),
                       "--json", summary]
                subprocess.run(cmd, check=True)
                with open(summary) as f:
                    run = json.load(f)
                labels[device] = f"cltrace {run['device']}"
                if k > 0:
                    cltrace_times[device].append(run["sampling_ms"] / 1e3)
        samples = w * h * args.spp
        rows.append((name, f"Mitsuba {mi.__version__} {args.variant}", samples / np.median(mitsuba_times) / 1e6, []))
        for device in devices:
            ratios = [m / c for m, c in zip(mitsuba_times, cltrace_times[device])]
            rows.append((name, labels[device], samples / np.median(cltrace_times[device]) / 1e6, ratios))
    print(f"{w}x{h}, {args.spp} spp, {args.max_bounces} bounces ({args.max_bounces + 2} segments), "
          f"Russian roulette after bounce 3, median of {args.repetitions}, renderers alternated")
    print("| scene | renderer | Msamples/s | of Mitsuba's | each repetition |")
    print("|---|---|---:|---:|---|")
    for name, who, rate, ratios in rows:
        base = next(r for n, wh, r, _ in rows if n == name and wh.startswith("Mitsuba"))
        each = ", ".join(f"{r:.2f}" for r in ratios)
        print(f"| {name} | {who} | {rate:.3f} | {rate / base:.2f}x | {each} |")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("scenes", help="write each scene's cltrace inputs (OBJ, MTL, scene.toml)")
    s.add_argument("--out", required=True)
    s.add_argument("--size", default="64x64")
    s.add_argument("--spp", type=int, default=1024, help="the scene files' spp")
    s.add_argument("--scenes", help="comma-separated names (default: all)")
    s.set_defaults(run=cmd_scenes)
    r = sub.add_parser("reference", help="write the inputs and render the Mitsuba references")
    r.add_argument("--out", required=True)
    r.add_argument("--spp", type=int, default=4096, help="Mitsuba's samples per pixel per half")
    r.add_argument("--size", default="64x64")
    r.add_argument("--scenes", help="comma-separated names (default: all)")
    r.add_argument("--max-bounces", type=int, help="override the scenes' max_bounces (cltrace's count)")
    r.add_argument("--check-spp", type=int, default=1024, help="the scene files' spp")
    r.set_defaults(run=cmd_reference)
    c = sub.add_parser("check", help="render the references' scenes with cltrace and compare")
    c.add_argument("--cltrace", required=True, help="the cltrace binary")
    c.add_argument("--refs", required=True, help="a folder of scene folders (or one) with scene.json")
    c.add_argument("--spp", type=int, default=1024, help="cltrace's samples per pixel, both halves")
    c.add_argument("--scenes", help="comma-separated names (default: all found)")
    c.set_defaults(run=cmd_check)
    v = sub.add_parser("speed", help="samples per second of both renderers at equal settings")
    v.add_argument("--cltrace", required=True, help="the cltrace binary")
    v.add_argument("--devices", default="Portable Computing Language",
                   help="cltrace's devices (--device selectors), comma-separated, each measured")
    v.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba's variant (llvm_ad_rgb, cuda_ad_rgb)")
    v.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "cltrace-speed"))
    v.add_argument("--size", default="512x512")
    v.add_argument("--spp", type=int, default=64)
    v.add_argument("--max-bounces", type=int, default=8, help="cltrace's count; Mitsuba's max_depth is 2 more")
    v.add_argument("--scenes", default="cornell,gold,glass")
    v.add_argument("--repetitions", type=int, default=3)
    v.set_defaults(run=cmd_speed)
    args = p.parse_args()
    args.run(args)


if __name__ == "__main__":
    main()
