"""Small scenes for the GL reference images: one per shape, light type and feature."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

import omnirender as om

DATA = Path(__file__).resolve().parents[1] / "data_files"


def stage(*, eye=(2.6, 2.0, 3.6), center=(0, 0.1, 0), floor: bool = True, lights: bool = True) -> om.Node:
    """Camera, a key light and a fill light, and a floor."""
    s = om.Node("scene")
    s.add(om.Camera.look_at(eye=eye, center=center, fov=35))
    if lights:
        s.add(om.DirectionalLight(direction=(-0.5, -1.0, -0.6), intensity=0.8))
        s.add(om.PointLight(position=(-3, 2, 3), color=(0.55, 0.65, 1.0), intensity=0.4))
        s.add(om.AmbientLight(intensity=0.1))
    if floor:
        f = s.add(om.Node("floor"))
        f.add(om.Material(ambient=(0.55, 0.55, 0.58), diffuse=(0.55, 0.55, 0.58)))
        f.add(om.Box(size=(6, 0.1, 6), center=(0, -1.05, 0)))
    return s


def with_shape(shape: om.Shape, color=(0.95, 0.45, 0.3), **kw) -> om.Node:
    s = stage(**kw)
    n = s.add(om.Node("shape"))
    n.add(om.Material(diffuse=color, specular=(0.6, 0.6, 0.6), shininess=40))
    n.add(shape)
    return s


def triangle_set() -> om.Node:
    v = [(-1, -0.8, 0), (1, -0.8, 0), (0, 0.9, 0), (0, -0.8, -1)]
    c = [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0)]
    s = stage()
    s.add(om.TriangleSet(v, [(0, 1, 2), (1, 3, 2), (3, 0, 2)], colors=c))
    return s


def lines() -> om.Node:
    s = stage()
    n = s.add(om.Node("lines"))
    n.add(om.DrawStyle(line_width=3))
    n.add(om.Color(0.2, 0.9, 1.0))
    t = np.linspace(0, 4 * np.pi, 120)
    n.add(om.Polyline(np.stack([np.cos(t) * 0.9, t / (4 * np.pi) * 1.8 - 0.9, np.sin(t) * 0.9], axis=1)))
    m = s.add(om.Node("segments"))
    m.add(om.DrawStyle(line_width=2))
    m.add(om.LineSet([(-1, -0.9, -1), (1, -0.9, 1), (1, -0.9, -1), (-1, -0.9, 1)], colors=[(1, 1, 0)] * 4))
    return s


def points() -> om.Node:
    rng = np.random.default_rng(3)
    p = rng.normal(size=(150, 3)) * 0.5
    s = stage()
    s.add(om.PointSet(p, colors=np.clip(p * 0.8 + 0.5, 0, 1), sizes=np.full(150, 7.0)))
    return s


def heightfield() -> om.Node:
    z, x = np.mgrid[-1:1:24j, -1:1:24j]
    h = 0.35 * np.sin(3 * x) * np.cos(3 * z) - 0.6
    return with_shape(om.Heightfield(h, spacing=2 / 23), color=(0.4, 0.8, 0.4))


def text() -> om.Node:
    s = stage()
    n = s.add(om.Node("label"))
    n.add(om.Color(1, 1, 0.4))
    n.add(om.Text("omni", position=(-0.6, 0.3, 0), size=16))
    s.add(om.Color(0.5, 0.6, 0.9))
    s.add(om.Sphere(radius=0.4, center=(0, -0.5, 0)))
    return s


def volume() -> om.Node:
    z, y, x = np.mgrid[-1:1:32j, -1:1:32j, -1:1:32j]
    r = np.sqrt(x**2 + y**2 + z**2)
    data = np.exp(-(((r - 0.6) / 0.15) ** 2)) + 0.6 * np.exp(-((r / 0.25) ** 2))
    tf = [(0.0, (0.1, 0.3, 1, 0)), (0.5, (0.2, 0.8, 1, 0.08)), (1.0, (1, 0.8, 0.2, 0.7))]
    s = stage()
    s.add(om.Volume(data, spacing=1.8 / 31, transfer_function=tf))
    return s


def mesh_file() -> om.Node:
    s = stage()
    n = s.add(om.Node("mesh"))
    n.add(om.Rotation(30, (0, 1, 0)))
    n.add(om.MeshFile(DATA / "cube.obj"))
    return s


def light_scene(light: om.Light) -> om.Node:
    s = stage(lights=False)
    s.add(light)
    n = s.add(om.Node("objects"))
    n.add(om.Material(ambient=(0.9, 0.6, 0.3), diffuse=(0.9, 0.6, 0.3), specular=(0.5, 0.5, 0.5), shininess=30))
    n.add(om.Sphere(center=(-0.6, -0.4, 0), radius=0.55))
    m = s.add(om.Node("box"))
    m.add(om.Material(ambient=(0.3, 0.6, 0.9), diffuse=(0.3, 0.6, 0.9), specular=(0.5, 0.5, 0.5), shininess=30))
    m.add(om.Box(size=(0.8, 0.8, 0.8), center=(0.7, -0.6, -0.3)))
    return s


def transparency() -> om.Node:
    s = stage()
    for i, (color, z) in enumerate((((1, 0.2, 0.2), -0.8), ((0.2, 1, 0.2), 0.0), ((0.2, 0.4, 1), 0.8))):
        n = s.add(om.Node(f"t{i}"))
        n.add(om.Material(diffuse=color, opacity=0.5))
        n.add(om.Sphere(center=(z * 0.7, -0.3, z), radius=0.5))
    # added in front-to-back order on purpose: the engine must sort
    s.insert(len(s) - 3, s.remove(s.child("t2")))
    return s


def clip_planes() -> om.Node:
    s = stage()
    n = s.add(om.Node("clipped"))
    n.add(om.ClipPlane(normal=(1, 0.3, 0), offset=-0.2))
    n.add(om.ClipPlane(normal=(0, -1, 0), offset=-0.5))
    n.add(om.Material(diffuse=(0.9, 0.6, 0.2), specular=(0.5, 0.5, 0.5)))
    n.add(om.Sphere(radius=0.9, center=(0, -0.1, 0)))
    return s


def fog() -> om.Node:
    s = stage(eye=(0, 0.6, 5.5), center=(0, -0.3, 0))
    s.add(om.Fog(color=(0.16, 0.16, 0.17), start=3.0, end=9.0))
    for i in range(5):
        n = s.add(om.Node(f"c{i}"))
        n.add(om.Translation(-1.6 + i * 0.9, -0.6, 1.5 - i * 1.6))
        n.add(om.Color(0.9, 0.5, 0.2))
        n.add(om.Cylinder(radius=0.3, height=0.8))
    return s


def textures() -> om.Node:
    s = stage()
    n = s.add(om.Node("textured"))
    n.add(om.Texture(DATA / "checker.png", filter="nearest"))
    n.add(om.Color(1, 1, 1))
    n.add(om.Box(size=(1.2, 1.2, 1.2), center=(-0.5, -0.4, 0)))
    n.add(om.Sphere(center=(0.8, -0.5, 0.3), radius=0.5))
    return s


def wireframe() -> om.Node:
    s = stage()
    n = s.add(om.Node("wire"))
    n.add(om.DrawStyle(mode="wireframe"))
    n.add(om.Tessellation(1))  # coarse: at 96x72 the edges stay visibly apart
    n.add(om.Color(0.5, 0.8, 1.0))
    n.add(om.Torus(major_radius=0.8, minor_radius=0.3))
    return s


def pbr() -> om.Node:
    s = stage()
    for i, (metal, rough) in enumerate(((0.0, 0.3), (1.0, 0.25), (1.0, 0.7))):
        n = s.add(om.Node(f"p{i}"))
        n.add(om.PBRMaterial(base_color=(0.95, 0.7, 0.3), metallic=metal, roughness=rough))
        n.add(om.Sphere(center=(-1.0 + i, -0.55, 0), radius=0.42))
    return s


def flat_and_highlight() -> om.Node:
    s = stage()
    a = s.add(om.Node("flat"))
    a.add(om.DrawStyle(shading="flat"))
    a.add(om.Tessellation(0))
    a.add(om.Translation(-0.6, -0.4, 0))
    a.add(om.Color(0.3, 0.7, 0.9))
    a.add(om.Torus(major_radius=0.45, minor_radius=0.2))
    b = s.add(om.Node("highlight"))
    b.add(om.Highlight(color=(1, 0.9, 0.1)))
    b.add(om.Color(0.6, 0.2, 0.8))
    b.add(om.Sphere(center=(0.7, -0.5, 0), radius=0.45))
    return s


SCENES: dict[str, Callable[[], om.Node]] = {
    "shape_sphere": lambda: with_shape(om.Sphere(radius=0.8, center=(0, -0.2, 0))),
    "shape_box": lambda: with_shape(om.Box(size=(1.2, 1.0, 0.8), center=(0, -0.5, 0))),
    "shape_cylinder": lambda: with_shape(om.Cylinder(radius=0.6, height=1.4)),
    "shape_cone": lambda: with_shape(om.Cone(radius=0.7, height=1.5)),
    "shape_torus": lambda: with_shape(om.Torus(major_radius=0.8, minor_radius=0.3)),
    "shape_disk": lambda: with_shape(om.Disk(radius=0.9)),
    "shape_rectangle": lambda: with_shape(om.Rectangle(size=(1.6, 1.0))),
    "shape_arrow": lambda: with_shape(om.Arrow(start=(-0.8, -0.8, 0), end=(0.8, 0.8, 0), radius=0.08)),
    "shape_polygon": lambda: with_shape(
        om.Polygon([(-0.8, -0.9, 0), (0.8, -0.9, 0), (1, 0.4, 0), (0, 1, 0), (-1, 0.4, 0)])
    ),
    "shape_triangle_set": triangle_set,
    "shape_lines": lines,
    "shape_points": points,
    "shape_heightfield": heightfield,
    "shape_text": text,
    "shape_volume": volume,
    "shape_mesh_file": mesh_file,
    "light_directional": lambda: light_scene(om.DirectionalLight(direction=(-1, -1, -0.5))),
    "light_point": lambda: light_scene(om.PointLight(position=(0.5, 1.2, 1.0), quadratic=0.3)),
    "light_spot": lambda: light_scene(
        om.SpotLight(position=(0, 2.5, 0.5), direction=(0, -1, -0.2), cutoff=25, exponent=4)
    ),
    "light_ambient": lambda: light_scene(om.AmbientLight(intensity=0.8)),
    "transparency": transparency,
    "clip_planes": clip_planes,
    "fog": fog,
    "textures": textures,
    "wireframe": wireframe,
    "pbr": pbr,
    "flat_and_highlight": flat_and_highlight,
}


# -- issue 10: the VRS techniques ------------------------------------------------------------
def technique_scene(*techniques: om.Component, mirror: bool = False) -> om.Node:
    """The stage with a ball and a ring after ``techniques`` (in one node), the floor a mirror if asked."""
    s = stage()
    if mirror:
        floor = s["/floor"]
        floor.insert(1, om.Mirror(0.6))
    body = s.add(om.Node("body", list(techniques)))
    body.add(om.Node("ball", [om.Material(diffuse=(0.95, 0.45, 0.3), specular=(0.6, 0.6, 0.6), shininess=40),
                              om.Sphere(center=(-0.5, -0.35, 0.2), radius=0.6)]))  # fmt: skip
    ring = [om.Translation(0.7, -0.4, -0.3), om.Rotation(60, (1, 0, 0)), om.Material(diffuse=(0.3, 0.5, 0.95))]
    body.add(om.Node("ring", [*ring, om.Torus(major_radius=0.45, minor_radius=0.15)]))
    return s


def csg() -> om.Node:
    s = stage()
    solid = om.CSG("difference", om.Sphere(radius=0.8), om.Box(size=0.9, center=(0.45, 0.45, 0.45)))
    s.add(om.Node("solid", [om.Material(diffuse=(0.9, 0.7, 0.3)), om.Translation(0, -0.2, 0), solid]))
    return s


def _lobe() -> om.Texture:
    return om.Texture(om.gl.PhongHighlight.lobe(30))


SCENES.update(
    {
        "technique_shadow_volumes": lambda: om.Node("root", [om.gl.ShadowVolumes(), technique_scene()]),
        "technique_mirror": lambda: technique_scene(mirror=True),
        "technique_silhouette": lambda: technique_scene(om.gl.SurfaceStyle("silhouette", width=2)),
        "technique_haloed": lambda: technique_scene(om.gl.SurfaceStyle("haloed", width=1, halo=2), om.Tessellation(1)),
        "technique_hidden_line": lambda: technique_scene(
            om.gl.SurfaceStyle("hidden-line", width=1), om.Tessellation(1)
        ),
        "technique_phong_highlight": lambda: technique_scene(om.gl.PhongHighlight(_lobe())),
        "technique_supersample": lambda: technique_scene(om.gl.Supersample(4)),
        "technique_shadow_maps_soft": lambda: om.Node("root", [om.gl.ShadowMaps(softness=3), technique_scene()]),
        "shape_csg": csg,
    }
)
