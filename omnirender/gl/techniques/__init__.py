"""GL techniques: multi-pass effects built on the engine's pass language (``gl.engine``).

``forward`` (the default technique), ``shadows`` (shadow maps), ``shadow_volumes``,
``mirrors``, ``stereo``, ``surface_style`` (line styles), ``highlight``, ``supersample``
and ``refraction``.  They import ``gl.engine`` (and each other), never the
``GLEngine`` facade nor the painters.  Their public names are ``om.gl.X``.
"""
