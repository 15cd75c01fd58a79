"""The post-processing chain: a GL technique whose passes render the scene in linear HDR and apply effects.

``om.gl.PostProcess([om.gl.SSAO(), om.gl.Bloom(), om.gl.ToneMap("aces"), om.gl.FXAA()])`` at the top of
the scene's root node post-processes every frame; the order is the user's, and an effect may appear
any number of times.  Its passes (all ``om.gl.Pass`` data; see ``engine.stats["passes"]``):

1. ``scene``: the opaque items, drawn by the frame's pipeline (forward, or deferred with
   ``GLEngine(pipeline="deferred")``) into a linear half-float target with depth (multisampled as the
   engine is, then ``resolve``d by a shader: samples are averaged in linear light, on every driver alike);
2. the ``"depth"`` stage: effects that read depth and normals (SSAO, fog, light shafts, depth of field),
   ping-ponging between two float targets: the depth they read is that of the colours they change;
3. ``transparent``: the transparent items composited by the engine's technique over that image, with
   the scene's depth (guacamole's post-processing read a depth that did not match its colours here);
4. the ``"color"`` stage: colour-only effects (bloom, tone mapping, vignette, grading, FXAA, user effects);
5. ``output``: the image into the frame, sRGB-encoded (linear into a float frame), with the scene's
   depth, so depth read-back, masks and later compositing see the same surfaces as without the chain;
6. ``overlay``: 2D items (text) over the result, untouched by the effects.

Without a ``ToneMap`` the output clamps the light to [0, 1] as the frame without a chain does.  The
effects' targets are single-sampled: transparent surfaces composited after the resolve are not
multisampled (``FXAA`` smooths every edge).  Other engines ignore the chain
(it is a GL technique); the offline engines warn that they do (see ``docs/NOTES.md``).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np

from ..engine.passes import Clear, FullScreen, Pass, Target
from ..engine.technique import GLTechnique
from . import glsl
from .effects import STAGES, Effect, EffectFrame

__all__ = ["PostProcess", "SCENE", "chain_effects"]

#: The target the scene is drawn into: linear half floats and the depth every effect reads.
SCENE = Target("postfx.scene", colors=("color",), depth=True, dtype="f2")
#: The target transparent items are composited into after depth effects ran (the scene's depth, shared).
_LATE = Target("postfx.late", colors=("color",), depth=SCENE.name, dtype="f2")
_MSAA = "postfx.msaa"
_PING = (Target("postfx.a", depth=False, dtype="f2"), Target("postfx.b", depth=False, dtype="f2"))


def chain_effects(effects: Any) -> tuple[Effect, ...]:
    """The effects of a chain as a tuple, each checked to be an ``om.gl`` effect and the stages in order."""
    if isinstance(effects, Effect):
        effects = (effects,)
    try:
        found = tuple(effects)
    except TypeError:
        raise ValueError(
            f"PostProcess: effects must be a list of effects (om.gl.SSAO(), ...), got {effects!r:.60}"
        ) from None
    for k, effect in enumerate(found):
        if not isinstance(effect, Effect):
            raise ValueError(
                f"PostProcess: effect {k} is {effect!r:.60}, not a post-processing effect; give om.gl.FXAA(), "
                "om.gl.ToneMap(), om.gl.Bloom(), om.gl.SSAO(), om.gl.DepthFog(), om.gl.Vignette(), "
                "om.gl.LightShafts(), om.gl.DepthOfField(), om.gl.ColorGrading() or om.gl.CustomEffect(...)"
            )
    for k in range(1, len(found)):
        if STAGES.index(found[k].stage) < STAGES.index(found[k - 1].stage):
            raise ValueError(
                f"PostProcess: effect {k} ({_name(found[k])}) reads depth but follows the colour-only effect "
                f"{_name(found[k - 1])}; depth effects run before transparent surfaces are composited, so list "
                "them first (e.g. SSAO, DepthFog, LightShafts, DepthOfField before Bloom, ToneMap, FXAA)"
            )
    return found


def _name(effect: Effect) -> str:
    label = getattr(effect, "name", None)
    kind = f"om.gl.{type(effect).__name__}"
    return f"{kind} {label!r}" if isinstance(label, str) else kind


class PostProcess(GLTechnique):
    """A user-ordered chain of post-processing effects over the rest of its node (see the module docstring).

    At the top of the root node it runs around the frame's pipeline; elsewhere it post-processes what it
    scopes and merges the result into the frame by depth (drawn by the forward technique).
    """

    __slots__ = ("effects", "_around_pipeline")
    #: the frame runs it around its pipeline when it holds the whole scene
    frame_level = True

    def __init__(self, effects: Iterable[Effect] = ()) -> None:
        super().__init__(passes=1)
        object.__setattr__(self, "_around_pipeline", False)
        found = chain_effects(effects)
        self.effects = found
        for effect in found:
            effect.attach_owner(self)

    def node_path(self) -> str:
        """The path of the (first) node holding the chain, for messages."""
        owners = self.owners
        return owners[0].path if owners else "(not in a node)"

    def supported(self, engine: Any) -> bool:
        """GL engines run the chain; engines that make images or files (POV-Ray, Mitsuba, Radiance, glTF, RIB)
        render the scene without it and warn; analysis engines (picking, bounds) ignore it silently."""
        if super().supported(engine):
            return True
        service = str(getattr(engine, "service", "") or "")
        if service.endswith((".paint", ".export")):
            warnings.warn(
                f"{type(engine).__name__} ignores the post-processing chain at {self.node_path()} "
                f"({', '.join(_name(e) for e in self.effects) or 'no effects'}): its effects are OpenGL image-space "
                "passes; this image or file shows the scene without them",
                stacklevel=2,
            )
        return False

    # -- pass control ----------------------------------------------------------------------------------------
    @property
    def deferred_inline(self) -> bool:
        """Whether the deferred pipeline shades what the chain scopes through its G-buffer: while the chain runs
        around the pipeline (at the top of the scene); a chain lower in the graph is drawn by the forward passes
        of the deferred frame, as other techniques are, and post-processes what it scopes."""
        return self._around_pipeline

    def start(self, engine: Any) -> None:
        plan = self.plan(engine)
        engine.technique_frame.data["plan"] = plan
        object.__setattr__(self, "_around_pipeline", plan[0].technique == "pipeline")

    def stop(self, engine: Any) -> None:
        object.__setattr__(self, "_around_pipeline", False)

    def needs_pass(self, engine: Any) -> bool:
        return engine.current_pass < len(engine.technique_frame.data["plan"])

    def prepare_pass(self, engine: Any) -> None:
        engine.set_pass(engine.technique_frame.data["plan"][engine.current_pass])

    def plan(self, engine: Any) -> list[Pass]:
        """This frame's passes: scene, depth effects, transparent items, colour effects, output, overlay."""
        top = engine.at_frame_level()
        proj = engine.frame_projection
        camera = {"u_proj": tuple(proj.T.ravel()), "u_inv_proj": tuple(np.linalg.inv(proj).T.ravel())}
        background = engine.clear_color(engine.frame_background)  # draw(background=...) wins
        clear = Clear(color=background, depth=1.0)
        drawn_by = "pipeline" if top else "engine"
        samples = int(getattr(engine, "samples", 0) or 0)
        if samples > 1:  # the engine's multisampling: the opaque scene drawn multisampled, then resolved
            msaa = Target(_MSAA, colors=("color",), depth=True, dtype="f2", samples=samples)
            passes = [
                Pass("scene", items="opaque", target=msaa, clear=clear, technique=drawn_by),
                Pass(
                    "resolve",
                    target=SCENE,
                    fullscreen=FullScreen(
                        glsl.RESOLVE_SAMPLES,
                        inputs={"u_samples": (_MSAA, "color"), "u_depths": (_MSAA, "depth")},
                        uniforms={"u_count": samples},
                        depth=True,
                        label="the multisampled scene's resolve",
                    ),
                ),
            ]
        else:
            passes = [Pass("scene", items="opaque", target=SCENE, clear=clear, technique=drawn_by)]

        depth = (SCENE.name, "depth")
        source = (SCENE.name, "color")
        step = 0
        where = self.node_path()
        stages = {stage: [(k, e) for k, e in enumerate(self.effects) if e.stage == stage] for stage in STAGES}
        for stage in STAGES:
            if stage == "color":  # transparent surfaces between the stages, over the depth stage's image
                if source[0] != SCENE.name:
                    copy = FullScreen(glsl.COPY, inputs={"u_input": source})
                    passes.append(Pass("composite", target=_LATE, fullscreen=copy))
                    late = _LATE
                else:
                    late = SCENE
                passes.append(Pass("transparent", items="transparent", target=late, technique="engine"))
                source = (late.name, "color")
            for k, effect in stages[stage]:
                output = _PING[step % 2]
                label = (
                    f"{_name(effect)} (effect {k} of the post-processing chain at {where}); fix its parameters "
                    "or its GLSL snippet"
                )
                frame = EffectFrame(engine, source, depth, output, f"postfx.{k}", label, camera)
                try:
                    made = effect.passes(frame)
                except ValueError as exc:
                    raise ValueError(f"{label}: {exc}") from None
                if made:  # an effect with nothing to do (light shafts without lights) passes the image on
                    passes.extend(made)
                    source = (output.name, "color")
                    step += 1
        output = FullScreen(
            glsl.OUTPUT,
            inputs={"u_input": source, "u_depth": depth},
            uniforms={"u_linear": 1.0 if engine.linear_output else 0.0},
            depth=True,
            depth_test="lequal",
            label=f"the output of the post-processing chain at {where}",
        )
        passes.append(Pass("output", fullscreen=output))
        passes.append(Pass("overlay", items="overlay", technique="engine"))
        return passes
