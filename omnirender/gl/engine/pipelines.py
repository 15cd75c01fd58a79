"""Chained pipelines in the GL engine: render textures drawn before the frame, in dependency order.

Every :class:`~.render_texture.RenderTexture` a frame uses is a pipeline: a
GL engine of its own (its compiled draw list, lights, camera, technique) on
the frame engine's context, drawing into a pair of sRGB textures.  Before a
frame is drawn, :meth:`PipelineSet.prepare` visits the render textures of the
compiled draw list depth first: a pipeline's own render textures are drawn
before it (that is the automatic order of the dependency graph), a pipeline
met again while it is being drawn reads its previous image (its front
texture, while it draws into the back one; they swap afterwards), and a
pipeline met again deeper in the stack is a cycle
(:class:`~.render_texture.PipelineCycleError` names it).  Each pipeline is
drawn at most once per frame and not at all while its scene, camera and the
pipelines it reads are unchanged.  Render textures met only while drawing
(a pass shader's ``Shader(textures=...)``) are remembered and drawn before
every later frame; the first frame shows them black.
"""

from __future__ import annotations

import weakref
from typing import Any

from .context import blit
from .glenum import GL_MIRRORED_REPEAT, GL_SRGB8_ALPHA8, GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T
from .render_texture import RenderTexture, visit
from .resources import gpu_call

__all__ = ["PipelineSet", "GLPipeline", "apply_sampling", "GL_SRGB8_ALPHA8"]

#: GL_SRGB8_ALPHA8: texture texels are display values the GPU decodes before filtering.


def apply_sampling(ctx: Any, raw: Any, tex: Any, texture: Any) -> None:
    """Set the filter and wrap of the GL texture ``tex`` from an ``om.Texture``'s parameters (one rule)."""
    lin = texture.filter == "linear"
    mag = ctx.LINEAR if lin else ctx.NEAREST
    if texture.mipmap:
        minf = ctx.LINEAR_MIPMAP_LINEAR if lin else ctx.NEAREST_MIPMAP_NEAREST
    else:
        minf = mag
    tex.filter = (minf, mag)
    tex.repeat_x = tex.repeat_y = texture.wrap != "clamp"
    if texture.wrap == "mirror" and raw.available:
        # moderngl has no mirrored-repeat switch: set GL_MIRRORED_REPEAT on the bound texture
        tex.use(0)
        for pname in (GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T):
            raw.glTexParameteri(GL_TEXTURE_2D, pname, GL_MIRRORED_REPEAT)


class GLPipeline:
    """One render texture on a frame engine: its engine and its front/back textures."""

    def __init__(self, pipelines: PipelineSet, texture: RenderTexture) -> None:
        host = pipelines.host
        self.texture_ref = weakref.ref(texture)
        self.size = texture.size
        self.sampling = (texture.filter, texture.wrap, texture.mipmap)
        host.check_texture_size(f"RenderTexture {texture.name!r}", self.size, host.max_texture_size)
        self.engine = type(host)(  # a GLEngine like its host (the engine package never imports the facade)
            size=self.size, samples=host.samples, context=host.ctx, programs=host.programs, shadows=host.shadows
        )
        self.engine.share_pipelines(pipelines)  # its render textures are the frame's pipelines
        ctx = host.ctx
        self.textures = []
        self.fbos = []
        for _ in range(2):
            tex = gpu_call(ctx.texture, self.size, 4, internal_format=GL_SRGB8_ALPHA8, what="a render texture")
            apply_sampling(ctx, host.raw, tex, texture)
            fbo = ctx.framebuffer(color_attachments=[tex])
            fbo.clear(0.0, 0.0, 0.0, 1.0)  # black before the first image
            self.textures.append(tex)
            self.fbos.append(fbo)
        if texture.mipmap:
            for tex in self.textures:
                tex.build_mipmaps()
        self.front = 0
        #: the frame it was last drawn in, what its image was made from, and how often it was drawn
        self.frame = -1
        self.key: Any = None
        self.drawn = 0
        self.self_reading = False

    def matches(self, texture: RenderTexture) -> bool:
        return self.size == texture.size and self.sampling == (texture.filter, texture.wrap, texture.mipmap)

    @property
    def gl_texture(self) -> Any:
        """The texture readers sample: the last finished image."""
        return self.textures[self.front]

    def draw(self, texture: RenderTexture) -> None:
        """Draw the pipeline's scene into the back texture and make it the front one."""
        engine = self.engine
        back = 1 - self.front
        with engine.current():
            engine.draw(camera=texture.camera)
            blit(engine.raw, engine.framebuffer, self.fbos[back], self.size, True, False)
            if texture.mipmap:
                self.textures[back].build_mipmaps()
        self.front = back
        self.drawn += 1

    def release(self) -> None:
        for fbo in self.fbos:
            fbo.release()
        for tex in self.textures:
            tex.release()
        self.engine.release()


class PipelineSet:
    """The pipelines of one frame engine (shared by the engines of its pipelines)."""

    def __init__(self, host: Any) -> None:
        self.host = host
        self.pipelines: dict[int, GLPipeline] = {}
        self.frame = 0
        self.stack: list[RenderTexture] = []
        #: render textures met while drawing (pass shaders), drawn before every later frame
        self.met: dict[int, weakref.ref] = {}
        self._found: tuple[int, list[RenderTexture]] | None = None
        self.report: list[dict[str, Any]] = []

    @staticmethod
    def used_by(engine: Any) -> list[RenderTexture]:
        """The render textures in ``engine``'s compiled draw list (materials, texture layers), in order."""
        found: dict[int, RenderTexture] = {}
        for item in engine.draw_items:
            for _, texture, _ in item.state.textures:
                if isinstance(texture, RenderTexture):
                    found.setdefault(id(texture), texture)
        return list(found.values())

    def _needed_by_host(self) -> list[RenderTexture]:
        version = self.host.draw_list_version
        if self._found is None or self._found[0] != version:
            self._found = (version, self.used_by(self.host))
        met = [ref() for ref in self.met.values()]
        return self._found[1] + [t for t in met if t is not None]

    def prepare(self) -> None:
        """Draw every pipeline the host's next frame reads (see the module docs).

        The host's ``stats["pipelines"]`` lists them in the order they were visited
        (dependencies first): name, whether it was drawn this frame, its passes.
        """
        self.frame += 1
        self.report: list[dict[str, Any]] = []
        for texture in self._needed_by_host():
            self._visit(texture)
        self.host.stats["pipelines"] = self.report
        for key in [k for k, p in self.pipelines.items() if p.frame != self.frame]:
            self.pipelines.pop(key).release()  # no longer used by the frame

    def _pipeline(self, texture: RenderTexture) -> GLPipeline:
        found = self.pipelines.get(id(texture))
        if found is not None and (found.texture_ref() is not texture or not found.matches(texture)):
            self.pipelines.pop(id(texture)).release()
            found = None
        if found is None:
            found = self.pipelines[id(texture)] = GLPipeline(self, texture)
        return found

    def _visit(self, texture: RenderTexture) -> None:
        if visit(self.stack, texture) == "self":
            self.pipelines[id(texture)].self_reading = True
            return
        pipeline = self._pipeline(texture)
        if pipeline.frame == self.frame:
            return
        self.stack.append(texture)
        try:
            engine = pipeline.engine
            camera = texture.camera
            with engine.current():  # the pipeline's camera shows what its group mask lets through, as in om.render
                engine.compile(texture.scene, mask=camera.mask if camera is not None and camera.mask else None)
            pipeline.self_reading = False
            deps = self.used_by(engine)
            for dep in deps:
                self._visit(dep)
            key = (texture.content_key(), tuple((id(d), self.pipelines[id(d)].drawn) for d in deps if d is not texture))
            drawn = pipeline.self_reading or key != pipeline.key
            if drawn:
                pipeline.draw(texture)
                pipeline.key = key
            pipeline.frame = self.frame
            passes = [p["name"] for p in engine.stats.get("passes", [])] if drawn else []
            self.report.append({"name": texture.name, "drawn": drawn, "passes": passes})
        finally:
            self.stack.pop()

    def texture(self, texture: RenderTexture) -> Any:
        """The GL texture of ``texture`` for a draw: its pipeline's front image (black if never drawn)."""
        pipeline = self.pipelines.get(id(texture))
        if pipeline is None or pipeline.texture_ref() is not texture:
            self.met[id(texture)] = weakref.ref(texture)  # a pass shader's: drawn before the next frames
            pipeline = self._pipeline(texture)
        return pipeline.gl_texture

    def image(self, texture: RenderTexture) -> Any:
        """The pipeline's last image as an ``om.Image`` (read back from its front texture)."""
        import numpy as np

        from ...image import Image

        pipeline = self.pipelines.get(id(texture))
        if pipeline is None:
            raise KeyError(f"GLEngine: {texture.name} was not drawn by this engine (no frame used it yet)")
        data = pipeline.gl_texture.read(alignment=1)
        w, h = pipeline.size
        return Image(np.frombuffer(data, np.uint8).reshape(h, w, 4)[::-1].copy())

    def release(self) -> None:
        for pipeline in self.pipelines.values():
            pipeline.release()
        self.pipelines.clear()
