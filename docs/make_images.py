"""Regenerate the pictures shown in README.md (docs/images/).

Run: .venv/bin/python docs/make_images.py [demo] [agreement] [materials] [gallery] [examples] [compositing]
     [transparency] [deferred] [postfx] [pipelines] [assets] [splats]
It renders the demo scene with every available engine, puts the images side by
side with labels, and runs the examples, copying their images here.  Naming
sections makes only those pictures (default: all).
"""

from __future__ import annotations

import colorsys
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import omnirender as om
from omnirender.demo import demo_scene

HERE = Path(__file__).parent / "images"
ROOT = Path(__file__).parent.parent
LABELS = {
    "gl": "OpenGL (real time)",
    "povray": "POV-Ray 3.7",
    "mitsuba": "Mitsuba 3 (path traced)",
    "radiance": "Radiance (rpict)",
}
#: Each engine's options for the README pictures (anti-aliased, enough samples).
PICTURE_OPTIONS = {"mitsuba": {"spp": 128}, "povray": {"antialias": True}, "radiance": {"oversample": 3}}


def side_by_side(paths: list[Path], labels: list[str], out: Path, gap: int = 6) -> None:
    images = [Image.open(p).convert("RGB") for p in paths]
    w, h = images[0].size
    sheet = Image.new("RGB", (len(images) * w + (len(images) - 1) * gap, h), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (im, label) in enumerate(zip(images, labels, strict=True)):
        x = i * (w + gap)
        sheet.paste(im, (x, 0))
        draw.rectangle([x, 0, x + 8 + 7 * len(label), 20], fill=(0, 0, 0))
        draw.text((x + 5, 4), label, fill=(255, 255, 255))
    sheet.save(out)


def demo_images(size: tuple[int, int] = (480, 360)) -> None:
    scene = demo_scene()
    paths, labels = [], []
    for name, (ok, why) in om.engines().items():
        if not ok:
            print(f"{name}: skipped ({why})")
            continue
        options = PICTURE_OPTIONS.get(name, {})
        path = HERE / f"demo_{name}.png"
        om.render(scene, engine=name, size=size, **options).save(path)
        paths.append(path)
        labels.append(LABELS.get(name, name))
        print("wrote", path)
    side_by_side(paths, labels, HERE / "demo_engines.png")
    print("wrote", HERE / "demo_engines.png")


def gl_gallery(columns: int = 9, scale: int = 2) -> None:
    """A contact sheet of the GL engine's reference images (tests/gl/references)."""
    refs = sorted((ROOT / "tests" / "gl" / "references").glob("*.png"))
    if not refs:
        return
    w, h = Image.open(refs[0]).size
    w, h = w * scale, h * scale
    rows = -(-len(refs) // columns)
    label_h = 14
    sheet = Image.new("RGB", (columns * w, rows * (h + label_h)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, ref in enumerate(refs):
        x, y = (i % columns) * w, (i // columns) * (h + label_h)
        sheet.paste(Image.open(ref).convert("RGB").resize((w, h), Image.NEAREST), (x, y))
        draw.text((x + 3, y + h + 1), ref.stem.replace("shape_", "").replace("_", " "), fill=(0, 0, 0))
    sheet.save(HERE / "gl_gallery.png")
    print("wrote", HERE / "gl_gallery.png")


def agreement_images() -> None:
    """The agreement test's scene in every engine, objects on white (engines_side_by_side.png)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_engines_agree import SIZE, make_scene

    names = {"gl": "OpenGL", "povray": "POV-Ray", "mitsuba": "Mitsuba 3", "radiance": "Radiance"}
    tiles = []
    for name, (ok, _) in om.engines().items():
        if not ok or name not in names:
            continue
        options = {"povray": {"antialias": True}, "mitsuba": {"spp": 256}, "radiance": {"oversample": 3}}.get(name, {})
        img = om.render(make_scene(), engine=name, size=SIZE, **options)
        rgb = np.where(img.mask[:, :, None], img.rgb, 255).astype(np.uint8)
        tile = Image.fromarray(rgb, "RGB")
        tile.save(HERE / f"engines_{name}.png")
        tiles.append((name, tile))
    sheet = Image.new("RGB", (SIZE[0] * len(tiles), SIZE[1] + 24), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for i, (name, tile) in enumerate(tiles):
        sheet.paste(tile, (i * SIZE[0], 24))
        draw.text((i * SIZE[0] + 8, 6), names[name], fill=(0, 0, 0))
    sheet.save(HERE / "engines_side_by_side.png")
    print("wrote", HERE / "engines_side_by_side.png")


def material_images() -> None:
    """The material chart (omnirender.chart) in every engine, with the CIEDE2000 medians (material_chart.png)."""
    import itertools

    from omnirender.chart import CHART_PATCHES, CHART_SIZE, material_chart, patch_means
    from omnirender.colorimetry import cielab, delta_e2000

    names = {"gl": "OpenGL", "povray": "POV-Ray", "mitsuba": "Mitsuba 3", "radiance": "Radiance"}
    tiles, labs = [], {}
    for name, (ok, _) in om.engines().items():
        if not ok or name not in names:
            continue
        options = {"mitsuba": {"spp": 128}}.get(name, {})
        img = om.render(material_chart(), engine=name, size=CHART_SIZE, **options)
        labs[name] = cielab(patch_means(img))
        tiles.append((name, Image.fromarray(img.rgb, "RGB")))
    w, h = CHART_SIZE
    sheet = Image.new("RGB", (w * 2 + 6, (h + 24) * ((len(tiles) + 1) // 2)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for i, (name, tile) in enumerate(tiles):
        x, y = (i % 2) * (w + 6), (i // 2) * (h + 24)
        sheet.paste(tile, (x, y + 24))
        draw.text((x + 6, y + 6), names[name], fill=(0, 0, 0))
    sheet.save(HERE / "material_chart.png")
    print("wrote", HERE / "material_chart.png")
    for a, b in itertools.combinations(labs, 2):
        d = delta_e2000(labs[a], labs[b])
        worst = int(d.argmax())
        print(f"{a} vs {b}: median dE2000 {np.median(d):.2f}, worst {CHART_PATCHES[worst]!r} {d[worst]:.1f}")


def example_images() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        scripts = [*sorted((ROOT / "examples").glob("0*.py")), ROOT / "examples" / "11_turntable.py",
                   ROOT / "examples" / "12_assets.py"]  # fmt: skip
        for script in scripts:
            subprocess.run([sys.executable, str(script), tmp], check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
        for png in sorted([*Path(tmp).glob("0*.png"), *Path(tmp).glob("12-*.png")]):
            if png.stem in {"01-gl-preview", "01-povray-final"}:
                continue
            shutil.copy(png, HERE / f"example_{png.stem}.png")
            print("wrote", HERE / f"example_{png.stem}.png")
        shutil.copy(Path(tmp) / "11-turntable.gif", HERE / "example_11-turntable.gif")  # the README's animation
        print("wrote", HERE / "example_11-turntable.gif")


def compositing_images() -> None:
    """The renderer-tree examples (13 and 14)."""
    with tempfile.TemporaryDirectory() as tmp:
        for script in ("13_renderer_tree.py", "14_user_renderer.py"):
            subprocess.run([sys.executable, str(ROOT / "examples" / script), tmp], check=True, cwd=ROOT,
                           stdout=subprocess.DEVNULL)  # fmt: skip
        for png in sorted(Path(tmp).glob("1[34]-*.png")):
            shutil.copy(png, HERE / f"example_{png.stem}.png")
            print("wrote", HERE / f"example_{png.stem}.png")


def transparency_images(size: tuple[int, int] = (320, 240)) -> None:
    """Two translucent renderers that interleave (a ball half inside a box): the engine's sorted transparency of
    one scene, a depth group, the depth-peel group, and the box coloured by its distance to the ball."""
    C = om.compositing
    camera = om.Camera.look_at((0.6, 1.2, 5.0), (0.2, 0, 0), fov=40)
    light = om.PointLight(position=(3, 5, 4))
    red = om.Material(diffuse=(1, 0.3, 0.2), specular=(0.6, 0.6, 0.6), shininess=40, opacity=0.55)
    blue = om.Material(diffuse=(0.2, 0.45, 1), specular=(0.6, 0.6, 0.6), shininess=40, opacity=0.45)
    ball = [red, om.Sphere(center=(-0.2, 0, 0.2), radius=0.9)]
    box = [blue, om.Rotation(20, (0, 1, 0)), om.Box(size=(1.5, 1.5, 1.5), center=(0.6, 0, -0.2))]
    one = om.Node("scene", [camera, om.Background((0.15, 0.15, 0.18)), light, om.Node("b", ball), om.Node("x", box)])
    a = C.SceneRenderer(om.Node("ball", [light, *ball]))
    b = C.SceneRenderer(om.Node("box", [light, *box]))
    kw = dict(camera=camera, background=(0.15, 0.15, 0.18))
    pictures = {
        "sorted (one scene)": om.render(one, engine="gl", size=size),
        "DepthGroup": C.DepthGroup([b, a]).render(size, **kw),
        "DepthPeelGroup": C.DepthGroup([C.DepthPeelGroup([a, b])]).render(size, **kw),
        "DistanceGroup (box to ball)": C.DepthGroup([C.DistanceGroup([b, a], range=(0, 1.5))]).render(size, **kw),
    }
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, image in enumerate(pictures.values()):
            paths.append(Path(tmp) / f"{i}.png")
            image.save(paths[-1])
        side_by_side(paths, list(pictures), HERE / "compositing_transparency.png")
    print("wrote", HERE / "compositing_transparency.png")


def hundred_lights_scene(lights: int = 128, seed: int = 3) -> om.Node:
    """guacamole's Figure 7c idea: a grid of objects on a dark floor lit only by many small coloured lights,
    each marked by a small glowing ball (its emission, not a light of its own)."""
    rng = np.random.default_rng(seed)
    root = om.Node("scene", [om.Camera.look_at(eye=(0, 7.5, 11), center=(0, 0, 0.5), fov=45),
                             om.Background((0.02, 0.02, 0.03)), om.AmbientLight(intensity=0.04)])  # fmt: skip
    root.add(om.Node("floor", [om.Material(diffuse=(0.75, 0.75, 0.75), specular=(0.3,) * 3, shininess=40),
                               om.Box(size=(16, 0.2, 12), center=(0, -0.1, 0))]))  # fmt: skip
    shapes = (om.Sphere(radius=0.35), om.Box(size=0.6), om.Torus(major_radius=0.3, minor_radius=0.1))
    objects = root.add(om.Node("objects", [om.Material(diffuse=(0.85, 0.85, 0.85), specular=(0.5,) * 3)]))
    for i in range(15):
        for j in range(11):
            objects.add(om.Node(f"o{i}_{j}", [om.Translation(-7 + i, 0.35, -5 + j), shapes[(i + 2 * j) % 3]]))
    for k in range(lights):
        x, z = rng.uniform(-7.5, 7.5), rng.uniform(-5.5, 5.5)
        color = tuple(float(c) for c in colorsys.hsv_to_rgb(rng.uniform(), 0.85, 1.0))  # saturated hues
        lamp = root.add(om.Node(f"light{k}", [om.Translation(x, 0.3, z)]))
        lamp.add(om.PointLight(color=color, intensity=4.0, quadratic=100.0, casts_shadows=False))
        lamp.add(om.Material(diffuse=(0, 0, 0), ambient=(0, 0, 0), emission=color))
        lamp.add(om.Sphere(radius=0.04))
    return root


def deferred_images() -> None:
    """The deferred pipeline: a hundred lights, the two example shading models, a trimmed NURBS surface."""
    scene = hundred_lights_scene()
    path = HERE / "deferred_hundred_lights.png"
    om.render(scene, engine="gl", size=(960, 540), pipeline="deferred").save(path)
    print("wrote", path)
    with tempfile.TemporaryDirectory() as tmp:
        for script in ("15_toon_model.py", "16_see_through.py", "17_nurbs.py"):
            subprocess.run([sys.executable, str(ROOT / "examples" / script), tmp], check=True, cwd=ROOT,
                           stdout=subprocess.DEVNULL)  # fmt: skip
        for png in sorted(Path(tmp).glob("1[567]-*.png")):
            shutil.copy(png, HERE / f"example_{png.stem}.png")
            print("wrote", HERE / f"example_{png.stem}.png")


def postfx_images(size: tuple[int, int] = (480, 360)) -> None:
    """The demo scene without and with a post-processing chain (SSAO, bloom, tone mapping, FXAA); example 8."""
    chain = om.gl.PostProcess([om.gl.SSAO(radius=0.5), om.gl.Bloom(threshold=0.6, intensity=2.5),
                               om.gl.ToneMap("aces", exposure=0.25), om.gl.FXAA()])  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        plain, post = Path(tmp) / "plain.png", Path(tmp) / "post.png"
        om.render(demo_scene(), engine="gl", size=size).save(plain)
        om.render(om.Node("root", [chain, demo_scene()]), engine="gl", size=size).save(post)
        labels = ["GL, no chain", "SSAO + bloom + ACES tone mapping + FXAA"]
        side_by_side([plain, post], labels, HERE / "postfx_chain.png")
        print("wrote", HERE / "postfx_chain.png")
        subprocess.run([sys.executable, str(ROOT / "examples" / "08_custom_effect.py"), tmp], check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)  # fmt: skip
        shutil.copy(Path(tmp) / "08-custom-effect.png", HERE / "example_08-custom-effect.png")
        print("wrote", HERE / "example_08-custom-effect.png")


def pipeline_images() -> None:
    """The chained pipelines example (18: a portal and a security-camera screen) and a stereo pair of the demo."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, str(ROOT / "examples" / "18_portal.py"), tmp], check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)  # fmt: skip
        shutil.copy(Path(tmp) / "18-portal.png", HERE / "example_18-portal.png")
        print("wrote", HERE / "example_18-portal.png")
    stereo = om.gl.Stereo("side-by-side", eye_separation=0.35, convergence=7.5)
    om.render(demo_scene(), engine="gl", size=(960, 360), stereo=stereo).save(HERE / "stereo_demo.png")
    print("wrote", HERE / "stereo_demo.png")


def usd_images() -> None:
    """Example 19: a USD stage in the four engines."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, str(ROOT / "examples" / "19_usd.py"), tmp], check=True, cwd=ROOT,
                       stdout=subprocess.DEVNULL)  # fmt: skip
        shutil.copy(Path(tmp) / "19-usd.png", HERE / "example_19-usd.png")
        print("wrote", HERE / "example_19-usd.png")


def asset_suite_images(size: tuple[int, int] = (128, 96)) -> None:
    """The cross-engine asset suite (tests/asset_suite.py) as a contact sheet: one row per asset, one column per
    engine, each engine's IoU / mean CIEDE2000 against GL under its picture (asset_suite.png)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from asset_suite import ASSETS, OPTIONS, asset_scene, compare, write_assets

    names = {"gl": "OpenGL", "povray": "POV-Ray", "mitsuba": "Mitsuba 3", "radiance": "Radiance"}
    engines = [n for n, (ok, _) in om.engines().items() if ok and n in names]
    w, h = size
    label, head, row_h = 150, 20, h + 14
    sheet = Image.new("RGB", (label + w * len(engines), head + row_h * len(ASSETS)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for j, name in enumerate(engines):
        draw.text((label + j * w + 6, 4), names[name], fill=(0, 0, 0))
    with tempfile.TemporaryDirectory() as tmp:
        files = write_assets(Path(tmp))
        for i, (asset, path) in enumerate(files.items()):
            y = head + i * row_h
            draw.text((6, y + h // 2 - 6), asset, fill=(0, 0, 0))
            images = {n: om.render(asset_scene(path, size), engine=n, size=size, **OPTIONS.get(n, {})) for n in engines}
            for j, name in enumerate(engines):
                sheet.paste(Image.fromarray(images[name].rgb, "RGB"), (label + j * w, y))
                if name != "gl" and "gl" in images:
                    iou, de = compare(images[name], images["gl"])
                    draw.text((label + j * w + 4, y + h), f"IoU {iou:.3f}  dE {de:.1f}", fill=(0, 0, 0))
                    print(f"{asset:24s} {name:9s} IoU {iou:.3f} mean dE2000 {de:.1f}")
    sheet.save(HERE / "asset_suite.png")
    print("wrote", HERE / "asset_suite.png")


def area_light_images(size: tuple[int, int] = (320, 240)) -> None:
    """The area-light agreement scene (a rectangle light over a slab) in every engine (area_lights.png)."""
    sys.path.insert(0, str(ROOT / "tests"))
    import test_area_light_agreement as agree

    agree.SIZE = size
    names = {"gl": "OpenGL (LTC, soft shadows)", "povray": "POV-Ray (spotlight per point)",
             "mitsuba": "Mitsuba 3 area emitter",
             "radiance": "Radiance light polygon"}  # fmt: skip
    engines = [n for n in names if om.engines().get(n, (False, ""))[0]]
    pov = agree.masks("povray", "rect")[0] if "povray" in engines else None
    sheet = Image.new("RGB", (size[0] * len(engines), size[1] + 40), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for j, name in enumerate(engines):
        occluded, _ = agree.renders(name, "rect")
        sheet.paste(Image.fromarray(occluded.astype(np.uint8), "RGB"), (j * size[0], 40))
        draw.text((j * size[0] + 6, 4), names[name], fill=(0, 0, 0))
        if pov is not None and name != "povray":
            shadow, penumbra = agree.masks(name, "rect")
            score = agree.iou(shadow, pov)
            draw.text((j * size[0] + 6, 20), f"shadow IoU vs POV-Ray {score:.3f}", fill=(0, 0, 0))
            print(f"{name}: shadow IoU vs POV-Ray {score:.3f}, penumbra {penumbra.sum()} px")
    sheet.save(HERE / "area_lights.png")
    print("wrote", HERE / "area_lights.png")


def splat_images() -> None:
    """The README's Gaussian-splat block (a planet of splats with a box half inside), run as it is written."""
    import re

    text = (ROOT / "README.md").read_text()
    block = next(b for b in re.findall(r"```python\n(.*?)```", text, re.S) if "om.GaussianSplats(" in b)
    with tempfile.TemporaryDirectory() as tmp:
        exec(compile(block.replace('"splats.png"', repr(str(Path(tmp) / "splats.png"))), "README", "exec"), {})
        shutil.copy(Path(tmp) / "splats.png", HERE / "splats.png")
    print("wrote", HERE / "splats.png")


SECTIONS = {
    "demo": demo_images,
    "agreement": agreement_images,
    "materials": material_images,
    "gallery": gl_gallery,
    "examples": example_images,
    "compositing": compositing_images,
    "transparency": transparency_images,
    "postfx": postfx_images,
    "deferred": deferred_images,
    "pipelines": pipeline_images,
    "usd": usd_images,
    "assets": asset_suite_images,
    "arealights": area_light_images,
    "splats": splat_images,
}

if __name__ == "__main__":
    HERE.mkdir(exist_ok=True)
    unknown = [name for name in sys.argv[1:] if name not in SECTIONS]
    if unknown:
        sys.exit(f"unknown section(s) {unknown}; choose from {sorted(SECTIONS)}")
    for name in sys.argv[1:] or SECTIONS:
        SECTIONS[name]()
