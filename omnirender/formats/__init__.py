"""File formats: the importer and exporter of each format together, one module (or package) per format.

- :mod:`~omnirender.formats.gltf`: ``om.load_gltf`` (reader), the ``.glb``
  exporter (writer), GLB packing and ``EXT_mesh_gpu_instancing``;
- :mod:`~omnirender.formats.meshes`: OBJ, PLY, STL, OFF through trimesh (and
  :mod:`~omnirender.formats.obj`, plain OBJ files without trimesh) for
  ``om.MeshFile``;
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

register_mesh_reader((".obj", ".ply", ".stl", ".off", ".gltf", ".glb"), "omnirender.formats.meshes:read_mesh")
register_mesh_reader((TRIMESH_OBJECT,), "omnirender.formats.meshes:read_mesh")
register_scene_reader((".glb", ".gltf"), "omnirender.formats.gltf:load_gltf")

register_exporter(".glb", "omnirender.formats.gltf.writer:export", "glTF 2.0 binary")
register_exporter(".rib", "omnirender.formats.rib:export", "RenderMan RIB")
register_exporter(".html", "omnirender.formats.html:export", "self-contained web page (three.js, works offline)")
