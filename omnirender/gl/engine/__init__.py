"""The GL engine's internals: the collaborators ``om.gl.GLEngine`` is assembled from.

Context and GPU resources (``context``, ``resources``, ``glstate``, ``framebuffer``),
the declarative GL state (``state``, ``attributes``), the compile side (``compiler``,
``drawlist``, ``dynamic``, ``translations``, ``instancing``, ``geometry``, ``layout``), programs
(``shaders``, ``shadow_glsl``, ``lighting``), the pass language (``technique``,
``passes``, ``imagespace``) and the frame side (``renderer``, ``frame``,
``pipelines``, ``render_texture``).

Dependency rule: modules here import only each other and the rest of omnirender
(core, attributes, scene, ...), never ``gl.techniques``, ``gl.painters``,
``gl.deferred``, ``gl.post`` nor the ``GLEngine`` facade (``gl/glengine.py``);
those build on this package's public names.  ``tests/gl/test_layout.py`` checks it.
This package imports nothing on import (moderngl is imported when an engine is made).
"""
