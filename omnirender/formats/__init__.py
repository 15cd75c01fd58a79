"""File formats: the importer and exporter of each format together, one module (or package) per format.

- :mod:`~omnirender.formats.gltf`: ``om.load_gltf`` (reader), the ``.glb``
  exporter (writer), GLB packing and ``EXT_mesh_gpu_instancing``;
- :mod:`~omnirender.formats.meshes`: OBJ, PLY, STL, OFF through trimesh (and
  :mod:`~omnirender.formats.obj`, plain OBJ files without trimesh) for
  ``om.MeshFile``; a scene's surfaces written as one ``.obj``, ``.ply`` or ``.stl``;
- :mod:`~omnirender.formats.usd`: ``om.load_usd`` and the ``.usd``/``.usda``/
  ``.usdc``/``.usdz`` exporter, through ``usd-core``;
- :mod:`~omnirender.formats.rib`: RenderMan RIB; :mod:`~omnirender.formats.html`:
  a self-contained three.js page.

Importing this package only registers the formats (by extension, with
``"module:function"`` references): ``om.MeshFile`` readers, scene readers and
``om.export`` writers.  A format module is imported the first time a file of
its kind is read or written.  POV-Ray and Radiance scene text is written by
their engines (``omnirender.povray``, ``omnirender.radiance``).
"""

from __future__ import annotations

from ..render import register_exporter
from ..scene.readers import register_scene_reader
from ..shapes.files import TRIMESH_OBJECT, register_mesh_reader

#: OpenUSD files: text, binary (crate) and either, and zip packages.
USD_SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")

register_mesh_reader((".obj", ".ply", ".stl", ".off", ".gltf", ".glb"), "omnirender.formats.meshes:read_mesh")
register_mesh_reader((TRIMESH_OBJECT,), "omnirender.formats.meshes:read_mesh")
register_mesh_reader(USD_SUFFIXES, "omnirender.formats.usd:mesh_parts")
register_scene_reader((".glb", ".gltf"), "omnirender.formats.gltf:load_gltf")
register_scene_reader(USD_SUFFIXES, "omnirender.formats.usd:load_usd")

register_exporter(".glb", "omnirender.formats.gltf.writer:export", "glTF 2.0 binary")
for _suffix, _what in ((".usda", "text"), (".usdc", "binary"), (".usd", "binary"), (".usdz", "package")):
    register_exporter(_suffix, "omnirender.formats.usd.writer:export", f"OpenUSD stage ({_what})")
register_exporter(".rib", "omnirender.formats.rib:export", "RenderMan RIB")
register_exporter(".html", "omnirender.formats.html:export", "self-contained web page (three.js, works offline)")
register_exporter(".obj", "omnirender.formats.meshes:export", "Wavefront OBJ: every surface as one mesh (trimesh)")
register_exporter(".ply", "omnirender.formats.meshes:export", "PLY: every surface as one mesh with colours (trimesh)")
register_exporter(".stl", "omnirender.formats.meshes:export", "STL: every surface as one mesh, no colours (trimesh)")
