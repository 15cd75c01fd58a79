"""Compiling a scene into draw items (the GL engine's one traversal, through the core interpreter).

The GL engine evaluates the scene with the core's interpreter
(:meth:`~omnirender.core.engine.Engine.run`), on *local* node programs whose
child nodes are ``NODE`` ops, and hooks in where it needs to:

* :meth:`eval_node` caches the draw items of every node occurrence: a node
  whose version did not move, entered in an unchanged state, is replayed from
  the cache without traversal, so a frame where one child of a 10,000-child
  node changed recompiles only that child;
* :meth:`run_technique` opens a nested :class:`~.drawlist.Scope` for a
  technique and compiles what it scopes *once*; its passes run at draw time,
  every frame (:mod:`.frame`);
* ``on_enter`` / ``on_leave`` keep the group tags of the current path, which
  pass masks test.

Painters append draw items through :meth:`submit`; nothing here calls OpenGL.
The active GL state attributes are captured declaratively (:mod:`.state`),
materials into the named instance row (:mod:`.layout`).  Lights, camera and
background come from the core's cached pre-evaluation.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ...attributes import BumpMap, DrawStyle, Fog, Highlight, Material, MultiTexture, Texture
from ...attributes.photometry import linear_rgb
from ...attributes.surface import Appearance, appearance_key, decided_by, resolve_appearance
from ...core.component import ChangeJournal, RenderingComponent, version_key
from ...core.light import LightSwitch
from ...core.program import DEINSTALL, ENTER, LEAVE, POP, REMOVE, TECHNIQUE, compile_components
from ...core.transform import Transform, TranslationArray
from ...scene.node import Node, declarations_kept
from .attributes import CullFace, GLState
from .compile_state import CompileState
from .dirty import DIRTY_TRANSFORM, classify, restyle, restyles, transform_swaps
from .drawlist import DrawItem, DrawState, Scope, drawn_transparent
from .geometry import Geometry
from .instancing import instance_rows, mask_copies
from .layout import ROW, shading_model
from .shaders import LAYER_BLENDS
from .state import FillMode, LineWidth, kinds

__all__ = ["DrawListCompiler", "TextureSet", "linear_rgb"]

_DEFAULT_POINT_SIZE = float(DrawStyle().point_size)  # without a DrawStyle, points get its default size
_MODEL = ROW.slice("model")
#: moved transforms up to which a frame asks whether they place no declaration (scene.node.declarations_kept,
#: a Python step per transform) before pre-evaluating the scene (a walk of the changed paths only)
_ASK_KEPT = 64
_COLOR = ROW.slice("color")
_SHADING_MODEL = ROW.at("emission", "model")
_HIGHLIGHT_ON = ROW.at("highlight", "on")
_POINT_SIZE = ROW.at("point", "size")
FOG_MODES = {"linear": 0.0, "exp": 1.0, "exp2": 2.0}
#: the row's fields in the order a surface row is made in (``_material_row``: one list of floats)
_SURFACE_FIELDS = ("model", "color", "specular", "emission", "ambient", "pbr", "highlight", "point")
assert tuple((f.name, f.size) for f in ROW.fields) == tuple(
    zip(_SURFACE_FIELDS, (16, 4, 4, 4, 4, 4, 4, 4), strict=True)
)
assert _POINT_SIZE == ROW.offsets["point"]  # (the point size comes first)
assert (
    ROW.at("emission", "model") == ROW.offsets["emission"] + 3 and ROW.at("pbr", "material") == ROW.offsets["pbr"] + 2
)
_ZEROS4 = (0.0, 0.0, 0.0, 0.0)
_ZEROS16 = (0.0,) * 16


def _uv_matrix(texture: Any) -> tuple[float, ...]:
    """A texture's coordinate transform as a GLSL mat3 (column-major)."""
    return tuple(float(x) for x in texture.uv_matrix().T.ravel())


class TextureSet:
    """What an appearance needs from the GL state: textures to bind, program features, uniforms.

    ``textures`` are (sampler uniform, om.Texture, sRGB) triples; ``features``
    and ``uniforms`` apply where the shape has texture coordinates, ``alpha``
    and ``alpha_uniforms`` (cut-out, opaque alpha) everywhere.  ``key`` holds
    them all: two sets with equal keys give draw items the same draw state.
    """

    __slots__ = ("textures", "features", "uniforms", "uv1", "normal", "alpha", "alpha_uniforms", "base", "key")

    def __init__(self, app: Appearance) -> None:
        textures: list[tuple[str, Any, bool]] = []
        features: list[tuple[str, Any]] = []
        uniforms: list[tuple[str, Any]] = []

        def slot(feature: str, sampler: str, suffix: str, texture: Any, srgb: bool) -> None:
            textures.append((sampler, texture, srgb))
            if feature:
                features.append((feature, True))
            features.append((f"UVSET_{suffix.upper()}", int(texture.uv_set)))
            uniforms.append((f"u_uvm_{suffix}", _uv_matrix(texture)))

        self.base = app.texture
        if app.texture is not None:
            slot("TEXTURE", "u_texture", "base", app.texture, True)
        if app.layers:
            features.append(("LAYERS", len(app.layers)))
            for i, layer in enumerate(app.layers):
                slot("", f"u_layer{i}", f"layer{i}", layer.texture, True)
                features.append((f"LAYER_BLEND{i}", LAYER_BLENDS[layer.blend]))
                uniforms.append((f"u_layer_opacity{i}", float(layer.opacity)))
        normal, scale = app.normal_map()
        self.normal = normal is not None
        if normal is not None:
            slot("", "u_normal_texture", "normal", normal, False)
            uniforms.append(("u_normal_scale", float(scale)))
        if app.model == "pbr":
            if app.metallic_roughness_texture is not None:
                slot("MR_TEXTURE", "u_mr_texture", "mr", app.metallic_roughness_texture, False)
            if app.occlusion_texture is not None:
                slot("OCCLUSION_TEXTURE", "u_occlusion_texture", "occlusion", app.occlusion_texture, False)
                uniforms.append(("u_occlusion_strength", float(app.occlusion_strength)))
            if app.emissive_texture is not None:
                slot("EMISSIVE_TEXTURE", "u_emissive_texture", "emissive", app.emissive_texture, True)
        self.textures = tuple(textures)
        self.features = tuple(features)
        self.uniforms = tuple(uniforms)
        self.uv1 = any(t.uv_set == 1 for _, t, _ in textures)
        if app.alpha_mode == "mask":
            self.alpha: tuple[tuple[str, Any], ...] = (("ALPHA_MASK", True),)
            self.alpha_uniforms: tuple[tuple[str, Any], ...] = (("u_alpha_cutoff", float(app.alpha_cutoff)),)
        elif app.model == "pbr" and app.alpha_mode == "opaque":
            self.alpha, self.alpha_uniforms = (("ALPHA_OPAQUE", True),), ()
        else:
            self.alpha, self.alpha_uniforms = (), ()
        self.key = (self.textures, self.features, self.uniforms, self.uv1, self.normal, self.alpha,
                    self.alpha_uniforms, self.base)  # fmt: skip


#: (model, alpha mode, cut-off of a masked one) -> the one TextureSet of the appearances that sample no texture
_PLAIN_SETS: dict[tuple[Any, ...], TextureSet] = {}


def texture_set(app: Appearance) -> TextureSet:
    """``TextureSet(app)``; one shared set for the appearances that sample no texture (their sets differ only
    by what the model and the alpha mode decide): a Material replaced per frame makes none."""
    if (
        app.texture is None
        and not app.layers
        and app.bump is None
        and app.normal_texture is None
        and app.metallic_roughness_texture is None
        and app.occlusion_texture is None
        and app.emissive_texture is None
    ):
        key = (app.model, app.alpha_mode, app.alpha_cutoff if app.alpha_mode == "mask" else None)
        found = _PLAIN_SETS.get(key)
        if found is None:
            if len(_PLAIN_SETS) > 64:
                _PLAIN_SETS.clear()
            found = _PLAIN_SETS[key] = TextureSet(app)
        return found
    return TextureSet(app)


class _NodeEntry:
    """A node occurrence's contributions (items and scopes), valid while its version and own components hold."""

    __slots__ = ("ref", "version", "own", "entries")

    def __init__(self, node: Any, own: tuple, entries: list[Any]) -> None:
        self.ref = weakref.ref(node)
        self.version = node.version
        self.own = own
        self.entries = entries


def _colors_copy(source: Any) -> np.ndarray | None:
    """A copy of an instance set's colours as the application holds them (None without colours)."""
    colors = getattr(source, "colors", None)
    if colors is None:
        return None
    array = getattr(colors, "array", None)
    return np.array(colors.array() if callable(array) and not isinstance(colors, np.ndarray) else colors)


class _Bail(Exception):
    """A subtree compile met what it does not handle: the full compile runs instead."""


_UNDO = frozenset((POP, REMOVE, DEINSTALL))


def _below(node: Any, ids: set[int]) -> bool:
    """Whether ``node`` or one of its first-parent ancestors is among ``ids``."""
    up = node
    while up is not None:
        if id(up) in ids:
            return True
        up = up.parent
    return False


def _det3(m: np.ndarray) -> float:
    """The determinant of ``m[:3, :3]`` (Python floats: a tenth of ``np.linalg.det``'s cost for one matrix)."""
    (a, b, c, _), (d, e, f, _), (g, h, i, _) = m[:3].tolist()
    return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)


def _declares_below(declared: Any, ids: set[int]) -> bool:
    """Whether a component of ``declared`` (a light, the camera...) lies in a node among ``ids`` or below one
    (through any parent); True when that is not known (no declarations, a component held by a component)."""
    if declared is None:
        return True
    for component, _ in declared.placements:
        owners = component.owners
        todo = [owner for owner in owners if isinstance(owner, Node)]
        if len(todo) != len(owners):
            return True
        seen: set[int] = set()
        while todo:
            node = todo.pop()
            if id(node) in ids:
                return True
            if id(node) not in seen:
                seen.add(id(node))
                todo.extend(node.parents)
    return False


def _same_declarations(a: Any, b: Any) -> bool:
    """Whether two pre-evaluations declare the same components (lights, camera, background) at the same places."""
    if a is None or b is None:
        return False
    if a is b:
        return True
    pa, pb = a.placements, b.placements
    return len(pa) == len(pb) and all(
        x is y and (m is n or bool((m == n).all())) for (x, m), (y, n) in zip(pa, pb, strict=True)
    )


class DrawListCompiler:
    """Compiles scenes into draw items: a collaborator of the GL engine that owns the compile state.

    Made once by :class:`~omnirender.gl.glengine.GLEngine` and handed the
    engine (whose public interpreter API runs the traversal: ``run``,
    ``run_program``, ``mono``, ``model_matrix``...), the
    :class:`~.renderer.BatchInstaller` that installs what it compiled, and the
    :class:`~.dynamic.TransformUpdater` that applies moved transforms without
    a traversal.  It owns the per-occurrence node cache, the change journal,
    the interned draw states and the :class:`~.compile_state.CompileState`
    attribute painters change (:attr:`state`).  The engine's interpreter hooks
    (``on_enter``, ``eval_node``, ``run_technique``) and the painters' calls
    (``submit``, ``capture``, ``submit_instances``) come here through the
    engine's methods of the same names.
    """

    def __init__(self, engine: Any, installer: Any, updater: Any, description: type | None = None) -> None:
        self.engine = engine
        self.installer = installer
        self.updater = updater
        #: the attribute class naming a surface's shading model and material description (the deferred
        #: pipeline's ``MaterialDescription``, handed in by the facade: the engine package imports no technique)
        self.description = description
        #: what attribute painters change (surface stack, clip planes, dirty flags)
        self.state = CompileState()
        self._immediate = Scope()  # what painters submit outside a compile (the viewer's frames)
        self._scope: Scope = self._immediate
        self._compile_frames: list[list[Any]] = []
        self._group_path: list[tuple[frozenset[str], ...]] = [()]
        self._technique_path: tuple[Any, ...] = ()
        self._node_cache: dict[int, Any] = {}
        #: (parent occurrence, ordinal) -> occurrence key of a node in the compiled graph
        self._occurrences: dict[tuple[int, int], int] = {}
        self._next_occurrence = 0
        #: id(node) -> (its occurrence key (-1: compiled more than once), ref), for compiling only edited subtrees
        self._occurrence_of: dict[int, tuple[int, Any]] = {}
        #: id(node) -> (ref, structure version, its components when they all precede its children, else None)
        self._leading_cache: dict[int, tuple[Any, int, Any]] = {}
        self._prune_limit = 4096
        self._compiled: tuple[Any, int, Any, int] | None = None  # (scene ref, version, mask key, structure)
        self._journal = ChangeJournal()  # what changed since the last frame (dynamic.py's fast path)
        self._full_key: Any = None
        self._state_base: tuple = ()
        self._states: dict[tuple, DrawState] = {}
        self._surface_row = np.zeros(ROW.stride, np.float32)
        self._surface_memo: dict[tuple, tuple[Any, ...]] = {}
        #: what the surface row reads besides the surface stack (texture, layers, bump, highlight, material
        #: description), read when the compile state's ``changes`` counter was ``_around_changes``
        self._around: tuple[Any, ...] = (None,) * 5
        self._around_changes = -1
        #: id(node) -> (ref, its leading components (the tuple _leading keeps), their program, their undo ops):
        #: the ancestors a splice enters
        self._leading_programs: dict[int, tuple[Any, tuple, list, list]] = {}
        #: ids of a splice's ancestors -> (their refs, versions, the resolved draw state where a child enters)
        self._entry_states: dict[tuple[int, ...], tuple[Any, ...]] = {}
        self._appearance: Any = None  # the resolved appearance and its texture set (set with the surface row)
        self._surface_entry: Any = None  # the surface_entry() the surface row was made from
        self._texset: Any = None
        self._point_size = 1.0
        self._blend_on = False
        self._alpha_tested = False
        self._auto_cull = True
        self._fill = "filled"
        self._kinds_seen = len(kinds())
        self._checked_textures: dict[int, tuple[Any, int]] = {}

    def install_immediate(self) -> None:
        """Install what painters submitted outside a compile (``render(None)``) and start a new immediate list."""
        self._journal.drain()  # nothing compiled to update in place: forget what changed
        self._journal.drain_edits()
        self.installer.install(self._immediate)
        self._immediate = Scope()
        self._scope = self._immediate
        self._compiled = None

    def forget(self) -> None:
        """Drop the node cache and what was compiled (the engine releases its GPU resources)."""
        self._node_cache.clear()
        self._compiled = None

    # -- the interpreter's hooks --------------------------------------------------
    def on_enter(self, node: Any) -> None:
        groups = node.groups
        stack = self._group_path
        stack.append(stack[-1] + (groups,) if groups else stack[-1])

    def on_leave(self, node: Any) -> None:
        self._group_path.pop()

    def eval_node(self, node: Any) -> Any:
        """A child node: replayed from the per-occurrence cache when unchanged, else its local program.

        Occurrences are keyed by small integers (parent occurrence, ordinal),
        so keys stay flat in graphs of any depth.
        """
        frames = self._compile_frames
        if frames:
            parent = frames[-1]
            parent[1] += 1
            pair = (parent[0], parent[1])
            key = self._occurrences.get(pair)
            if key is None:
                self._next_occurrence += 1
                key = self._occurrences[pair] = self._next_occurrence
            entry = self._node_cache.get(key)
            # an entry exists only for a node the (unchanged) mask admitted: the hit needs no mask test
            if entry is not None and not parent[2] and entry.ref() is node and entry.version == node.version:
                self._scope.entries.extend(entry.entries)
                return None
        groups = node.groups
        if groups and not self.engine.admits(groups):
            return None
        local = getattr(node, "local_program", None)
        if local is None or not frames:  # a viewer snapshot, or immediate mode: nothing to cache
            return node.program(), None
        scope = self._scope
        same = entry is not None and entry.ref() is node
        own = tuple([x if isinstance(x, Node) else (x, x.version) for x in node.items])
        frames.append([key, 0, parent[2] or not same or entry.own != own])
        start = len(scope.entries)

        def store() -> None:
            frames.pop()
            self._node_cache[key] = _NodeEntry(node, own, scope.entries[start:])
            found = self._occurrence_of.get(id(node))
            # several: this very node met again under another key (an entry of a node that died, whose address
            # a new node took, says nothing of the new one: it is replaced)
            several = found is not None and found[1]() is node and found[0] != key
            self._occurrence_of[id(node)] = (-1 if several else key, weakref.ref(node))  # -1: several

        return local(), store

    def run_technique(self, technique: Any, program: list[tuple[int, Any]]) -> None:
        """A technique's scope: compiled once into a nested Scope; its passes run when the frame is drawn."""
        if not technique.supported(self.engine):
            self.engine.run_program(program)  # ignored: what it scopes is evaluated once, as if it were not there
            return
        scope = Scope(technique)
        outer = self._scope
        outer.entries.append(scope)
        self._scope = scope
        previous = self.engine.technique
        self.engine.technique = technique  # its service and handler overrides apply to what it scopes
        path = self._technique_path
        self._technique_path = (*path, technique)
        try:
            self.engine.run_program(program)
        finally:
            self.engine.technique = previous
            self._scope = outer
            self._technique_path = path

    # -- compile ---------------------------------------------------------------------
    def compile(self, scene: Any, mask: Any = None) -> Scope:
        """Compile ``scene`` (a Node or components) into the root scope; cached while nothing changed."""
        if mask is not None:
            self.engine.mask = mask
        if not hasattr(scene, "local_program"):
            scene = Node.transient([scene] if isinstance(scene, RenderingComponent) else scene)
        mask_key = self.engine.mask
        c = self._compiled
        changed = self._journal.drain()
        edits = self._journal.drain_edits()
        if len(kinds()) != self._kinds_seen:
            self._new_state_kinds()
            c = None
        if c is not None and c[0]() is scene and c[2] == mask_key:
            version, structure = scene.versions
            if c[1] == version:
                self.engine.stats["compiled"] = False
                return self.installer.root
            if c[3] == structure:
                # only transforms moved or instance arrays changed: rewrite those rows, no traversal (dynamic.py)
                count = self.updater.apply(changed)
                if count is not None:
                    self.engine.stats["incremental"] = count
                    # lights and the camera may sit below a moved transform: the (incremental) pre-evaluation
                    # again (instance sets' arrays place neither: their declarations are kept); the graph walks
                    # only the changed paths; the last frame's result is kept when it is the same (a recorded
                    # frame plan keys on it: moves of plain objects keep it)
                    engine = self.engine
                    updater = self.updater
                    # (not when every moved transform sits in a node whose subtree declares nothing: a plain
                    # object moved places no light or camera, and the walk up to the root is skipped)
                    # (many moved: the pre-evaluation, which walks only the changed paths, costs less than asking)
                    moved, updater.moved = updater.moved, []  # (not held to the next frame: thousands, at times)
                    if updater.placed and (
                        len(moved) > _ASK_KEPT
                        or TranslationArray in map(type, moved)  # (an array's thousands of owners)
                        or not declarations_kept(moved, engine.mask_function)
                    ):
                        declared = engine.preevaluate(scene)
                        if not _same_declarations(engine.declared, declared):
                            engine.declared = declared
                            engine.camera = declared.camera
                    self._compiled = (c[0], version, mask_key, c[3])  # (applying moved nothing of the graph)
                    self.engine.stats["compiled"] = False
                    return self.installer.root
            elif edits and self.installer.root is not None and self._full_key is not None:
                # attributes replaced by ones of the same role: dirty bits on the items, rows patched (dirty.py)
                count = self._replace(scene, edits, changed)
                if count is not None:
                    self.engine.stats["incremental"] = count
                    version, structure = scene.versions
                    self._compiled = (c[0], version, mask_key, structure)
                    self.engine.stats["compiled"] = "dirty"
                    return self.installer.root
                # nodes added or removed, attributes replaced: compile only the subtrees the edits touch
                count = self._splice(scene, edits, changed)
                if count is not None:
                    self.engine.stats["incremental"] = count
                    self._compiled = (c[0], scene.version, mask_key, scene.structure_version)
                    self.engine.stats["compiled"] = "subtrees"
                    return self.installer.root
        self.engine.sync_registry()
        camera = scene.declarations(self.engine.mask_function).camera
        full_key = (mask_key, camera[0].mask if camera is not None else None)
        if c is None or c[0]() is not scene or c[2] != mask_key or self._full_key != full_key:
            self._node_cache.clear()
            self._occurrences.clear()
            self._occurrence_of.clear()
        self._full_key = full_key
        root = Scope(None)
        self._scope = root
        self._compile_frames = [[0, 0, False]]
        generation = self.engine.material_table.generation
        try:
            self.engine.run(scene)
            if self.engine.material_table.generation != generation:  # the material table started again: every id anew
                self._node_cache.clear()
                self._occurrence_of.clear()
                self._surface_memo.clear()
                self.state.invalidate()
                root = self._scope = Scope(None)
                self._compile_frames = [[0, 0, False]]
                self.engine.run(scene)
        except BaseException:
            self.state.clear()
            self._node_cache.clear()
            self._occurrence_of.clear()
            self._compiled = None
            raise
        finally:
            self._compile_frames = []
            self._scope = self._immediate
        self._compiled = (weakref.ref(scene), scene.version, mask_key, scene.structure_version)
        self._prune_caches()
        self.installer.install(root)
        self.engine.stats["compiled"] = True
        return root

    # -- attributes replaced by attributes of the same role: dirty bits (dirty.py) -------------
    def _replace(self, scene: Any, edits: list[Any], changed: list[Any]) -> int | None:
        """Apply the frame's list edits as dirty bits when they only replaced attributes by attributes of the
        same role (:func:`.dirty.classify`): transforms recompose the rows below them, surfaces rewrite the
        rows' surface fields; no subtree compile, no splice.  Returns how many items changed, or None (nothing
        modified) for the splice path.  Other components changed in the same frame may only be static
        transforms (moved with the others)."""
        replacements = classify(edits, self._entry_of)
        if replacements is None:
            return None
        moves: list[Any] = []
        if changed:
            replaced = {id(r.old) for r in replacements}
            replaced.update(id(r.new) for r in replacements)
            for c in changed:
                if id(c) in replaced or isinstance(c, Node) or not c.owners:  # (outside the scene: changes nothing)
                    continue
                if not (isinstance(c, Transform) and c.static):
                    return None  # a parameter changed beside the replacements: the splice compiles it
                moves.append(c)
        swaps = transform_swaps(replacements)
        if swaps is None:
            return None
        table = self.engine.material_table
        generation, version = table.generation, table.version
        changes = restyles(replacements, self.surface_entry)
        if changes is None or table.generation != generation:
            return None
        # every replacement is handled: from here on the draw list changes
        if swaps:
            self.updater.replace(swaps)
        count = 0
        if changes:
            batches, same = restyle(changes)
            self.updater.rows_rewritten(batches, same and table.version == version)
            count += len(changes)
        news = [r.new for r in replacements if r.kind == DIRTY_TRANSFORM]
        if news or moves:
            count += self.updater.apply([*news, *moves] if moves else news) or 0
            engine = self.engine
            # lights or the camera below a replaced or moved transform move with it: the declarations again (not
            # when the nodes of the replaced and the moved transforms declare nothing below them: the nodes'
            # own declaration results say so at once; else the declared components' ancestors are walked)
            mask_function, declared = engine.mask_function, engine.declared
            if (
                (declared is None or not declarations_kept(news, mask_function))
                and _declares_below(declared, {id(r.node) for r in replacements if r.kind == DIRTY_TRANSFORM})
            ) or (moves and not declarations_kept(moves, mask_function)):
                declared = engine.preevaluate(scene)
                if not _same_declarations(engine.declared, declared):
                    engine.declared = declared
                    engine.camera = declared.camera
        kinds: set[str] = set()
        for r in replacements:  # each node's entry: compiled with what it holds now
            kinds.add(r.kind)
            entry = r.entry
            entry.own = tuple([x if isinstance(x, Node) else (x, x.version) for x in r.node.items])
            entry.version = r.node.version
        self.engine.stats["dirty"] = tuple(sorted(kinds))
        return count

    def entries_of(self, node: Any) -> list[Any] | None:
        """The draw items and scopes ``node``'s one compiled occurrence made (its descendants' included), or
        None when it was not compiled once or its entry is gone."""
        entry = self._entry_of(node)
        return None if entry is None else entry.entries

    # -- compiling only the subtrees that list edits touched --------------------------------
    def _splice(self, scene: Any, edits: list[Any], changed: list[Any]) -> int | None:
        """Apply the list edits since the last frame by compiling only the subtrees they touch.

        Handles the edits of simulations and editors: child nodes appended to
        or removed from a node, components inserted or removed in a node
        without child nodes (an attribute replaced).  The state each subtree is
        compiled in is rebuilt by evaluating the components of its ancestors
        (their shapes go to a scope that is dropped): the ancestors must each
        hold their components before their child nodes and have one parent.
        The new items replace the old in their batches (``BatchInstaller.splice``).
        Returns how many items were removed and added, or None when the full
        compile must run (nothing installed has changed then).

        Transforms moved in the same frame (a simulation moving its objects
        while one comes or goes) are applied by the updater after the splice,
        wherever they are (the new subtrees were compiled with their values
        already; their rows are written again the same).
        """
        moves, rest = _moves_of(changed)
        if moves and self.updater.follows(moves):
            changed = rest
        else:
            moves = []  # (no plan to move rows with, or a clip plane moved: as any other change)
        plan = self._splice_plan(scene, edits, changed)
        if plan is None:
            return None
        leaves, groups = plan
        engine = self.engine
        old_declared = engine.declared
        generation = engine.material_table.generation
        removed: list[Any] = []
        added: list[Any] = []

        def compile_subtrees() -> None:  # run in the state scene's pre-evaluation makes (engine.run_partial)
            if not _same_declarations(old_declared, engine.declared):
                raise _Bail
            for node, key, path in leaves:
                removed.extend(self._node_cache[key].entries)
                added.extend(self._compile_at(node, key, path))
            for node, key, path, appended, gone in groups:
                for child in gone:
                    child_key = self._occurrence_of.pop(id(child))[0]
                    removed.extend(self._node_cache.pop(child_key).entries)
                for child in appended:
                    self._next_occurrence += 1
                    added.extend(self._compile_at(child, self._next_occurrence, (*path, node)))
                self._node_cache.pop(key, None)  # its list changed: compiled again by the next full compile
            if engine.material_table.generation != generation:
                raise _Bail

        try:
            engine.run_partial(scene, compile_subtrees)
        except BaseException:
            self._scope = self._immediate
            self._compile_frames = []
            self._node_cache.clear()  # some entries may be half made: the full compile starts afresh
            self._occurrence_of.clear()
            return None
        self._scope = self._immediate
        self._compile_frames = []
        engine.declared, engine.camera = old_declared, old_declared.camera  # the same (compile_subtrees checked)
        for _, _, path in leaves:
            for above in path:  # their flattened entries hold the old items: compiled again when next missed
                self._drop_entry(above)
        for _, _, path, _, _ in groups:
            for above in path:
                self._drop_entry(above)
        if not self.installer.splice(removed, added):
            self._node_cache.clear()
            self._occurrence_of.clear()
            return None
        count = len(removed) + len(added)
        if moves:
            moved = self.updater.apply(moves)
            if moved is None:  # (not expected: follows() said it would)
                return None
            count += moved
        return count

    def _drop_entry(self, node: Any) -> None:
        key = self._key_of(node)
        if key is not None:
            self._node_cache.pop(key, None)

    def _splice_plan(self, scene: Any, edits: list[Any], changed: list[Any]) -> tuple[list, list] | None:
        """Which nodes to compile again (leaves) and which children to add and remove, or None."""
        grouped = self._group_edits(edits)
        if grouped is None:
            return None
        leaves, groups, loose = grouped
        added_ids = {i for g in groups.values() for i in g[2]}
        removed_ids = {i for g in groups.values() for i in g[3]}
        for node in loose:  # edited, not compiled: inside a new subtree, or outside the scene
            up = node
            while up is not None and id(up) not in added_ids:
                if self._key_of(up) is not None:
                    return None  # below a compiled node without being compiled (masked?): not followed
                up = up.parent
        for c in changed:  # components changed since the last frame: only those the new subtrees hold
            if isinstance(c, Node) or not c.owners:
                continue
            for owner in c.owners:  # an owner may be a component built from it (an instance set's shape)
                if not isinstance(owner, Node) or (id(owner) not in leaves and not _below(owner, added_ids)):
                    return None
        leaf_list = []
        for node in leaves.values():
            own = self._own(node)
            if own is None or any(isinstance(x, Node) for x in (*node.items, *own)):
                return None
            path = self._path_to(scene, node)
            if path is None or _below(node, removed_ids):
                return None
            leaf_list.append((node, self._key_of(node), path))
        group_list = []
        for node, key, appended, gone in groups.values():
            tail = node.last_items(len(appended))
            if appended and (len(appended) > len(node) or {id(x) for x in tail} != set(appended)):
                return None  # not appended at the end
            if any(self._key_of(child) is None for child in gone.values()):
                return None
            path = self._path_to(scene, node)
            if path is None or _below(node, removed_ids):
                return None
            ordered = list(tail)
            group_list.append((node, key, path, ordered, list(gone.values())))
        return leaf_list, group_list

    def _group_edits(self, edits: list[Any]) -> tuple[dict, dict, list] | None:
        """The edits by node: (nodes whose components changed, compiled nodes whose children came or went (node,
        key, appended, removed), edited nodes not compiled), or None for an edit the splice does not follow."""
        leaves: dict[int, Any] = {}
        groups: dict[int, list[Any]] = {}
        loose: list[Any] = []
        places: dict[int, list[int]] = {}  # id(node) -> where its child nodes came or went
        for container, op, item, at in edits:
            if op not in ("insert", "remove") or not isinstance(container, Node):
                return None
            places.setdefault(id(container), []).append(at if isinstance(item, Node) else -1)
            key = self._key_of(container)
            if key is None:
                loose.append(container)
            elif not isinstance(item, Node):
                leaves[id(container)] = container
            else:
                _, _, appended, gone = groups.setdefault(id(container), [container, key, {}, {}])
                if op == "insert" and id(item) in gone:
                    return None  # moved within the list
                if op == "insert":
                    appended[id(item)] = item
                elif id(item) in appended:
                    del appended[id(item)]
                else:
                    gone[id(item)] = item
        if set(leaves) & set(groups):
            return None
        for node, _, _, _ in groups.values():
            self._carry_leading(node, places[id(node)])
        return leaves, groups, loose

    def _carry_leading(self, node: Any, places: list[int]) -> None:
        """``node``'s list changed only by child nodes coming or going at ``places``: its cached leading components
        stay what they were (no scan of a scene's thousands of children), as long as every child came after them.

        Each edit bumped ``node.list_version`` by one; a cache entry of the version before them is carried on.
        """
        found = self._leading_cache.get(id(node))
        version = node.list_version
        if found is None or found[0]() is not node or found[2] is None or found[1] != version - len(places):
            return
        if all(at >= len(found[2]) for at in places):
            self._leading_cache[id(node)] = (found[0], version, found[2])

    def _key_of(self, node: Any) -> int | None:
        """The occurrence key of ``node`` in the compiled graph, or None (not compiled, or compiled several times)."""
        found = self._occurrence_of.get(id(node))
        if found is None or found[0] < 0 or found[1]() is not node:
            return None
        return found[0]

    def _entry_of(self, node: Any) -> _NodeEntry | None:
        """What the last compile made of ``node`` (its own items as compiled, its entries), or None when it was
        not compiled once (or several times) or its entry is gone."""
        key = self._key_of(node)
        entry = None if key is None else self._node_cache.get(key)
        if entry is None or entry.ref() is not node:
            return None
        return entry

    def _own(self, node: Any) -> tuple | None:
        """The items ``node`` held when it was last compiled, or None when its entry is gone."""
        entry = self._entry_of(node)
        if entry is None:
            return None
        return tuple(x if isinstance(x, Node) else x[0] for x in entry.own)

    def _path_to(self, scene: Any, node: Any) -> tuple[Any, ...] | None:
        """The ancestors of ``node`` from ``scene`` down (one parent each, components before children), or None."""
        path = []
        up = node
        while up is not scene:
            parents = up.parents
            if len(parents) != 1:
                return None
            up = parents[0]
            if self._leading(up) is None:
                return None
            path.append(up)
        path.reverse()
        return tuple(path)

    def _leading(self, node: Any) -> tuple[Any, ...] | None:
        """``node``'s components when they all come before its child nodes (else None); cached per own list (a
        descendant's edit leaves it: replacing one node's attribute does not scan its parent's children again)."""
        version = node.list_version
        found = self._leading_cache.get(id(node))
        if found is not None and found[0]() is node and found[1] == version:
            return found[2]
        items = node.items
        types = list(map(type, items))
        first = types.index(Node) if Node in types else len(types)
        leading = items[:first] if types.count(Node) == len(types) - first else None
        if leading is not None and any(isinstance(x, Node) for x in leading):
            leading = None  # a Node subclass among them
        if len(self._leading_cache) > 4096:
            self._leading_cache.clear()
        self._leading_cache[id(node)] = (weakref.ref(node), version, leading)
        return leading

    def _compile_at(self, node: Any, key: int, path: tuple[Any, ...]) -> list[Any]:
        """Compile ``node`` (occurrence ``key``) in the state its ancestors ``path`` make; returns its entries."""
        ops = self.engine.ops
        sink = Scope()
        self._scope = sink
        undos = []
        leadings = []
        versions: list[int] = []
        for above in path:
            program, undo, leading = self._leading_program(above)
            ops[ENTER](above)
            for code, arg in program:
                ops[code](arg)
            undos.append(undo)
            leadings.append(leading)  # the tuple _leading keeps while the node's leading components are the same
            versions.extend([x.version for x in leading])
        self._enter_state(path, leadings, tuple(versions))
        target = Scope(None)
        self._scope = target
        own = tuple([x if isinstance(x, Node) else (x, x.version) for x in node.items])
        self._compile_frames = [[key, 0, True]]
        self.engine.run_program(node.local_program())
        self._compile_frames = []
        self._node_cache[key] = _NodeEntry(node, own, list(target.entries))
        self._occurrence_of[id(node)] = (key, weakref.ref(node))
        self._scope = sink
        for undo in reversed(undos):
            for code, arg in undo:
                ops[code](arg)
            ops[LEAVE](-1)
        return target.entries

    def _leading_program(self, node: Any) -> tuple[list, list, tuple]:
        """The ops of ``node``'s leading components (what its children are entered after), their undo ops, and
        the components; cached per own list.  A technique among them is not followed (raises _Bail)."""
        leading = self._leading(node)
        found = self._leading_programs.get(id(node))
        if found is not None and found[0]() is node and found[1] is leading:
            return found[2], found[3], leading
        program = compile_components(leading, [])
        if any(code == TECHNIQUE for code, _ in program):
            raise _Bail
        cut = len(program) - sum(1 for code, _ in program if code in _UNDO)
        if len(self._leading_programs) > 4096:
            self._leading_programs.clear()
        self._leading_programs[id(node)] = (weakref.ref(node), leading, program[:cut], program[cut:])
        return program[:cut], program[cut:], leading

    def _enter_state(self, path: tuple[Any, ...], leadings: list[tuple], versions: tuple[int, ...]) -> None:
        """Resolve the draw state where a child of ``path[-1]`` is entered (after the leading components
        ``leadings`` of its ancestors ran, at ``versions``): kept per path while those components and their
        versions are the same, so that frames adding a node under one parent resolve it once.  What the child's
        own attributes change is resolved again as usual (their painters mark the compile state dirty)."""
        key = tuple(map(id, path))
        found = self._entry_states.get(key)
        state = self.state
        if (
            found is not None
            and found[1] == versions
            and found[2] == self._kinds_seen
            and all(ref() is above for ref, above in zip(found[0], path, strict=True))
            and all(a is b for a, b in zip(found[4], leadings, strict=True))
        ):
            (self._state_base, self._fill, self._point_size, self._blend_on, self._alpha_tested,
             self._auto_cull, self._around) = found[3]  # fmt: skip
            self._around_changes = state.changes
            state.state_dirty = False
            state.surface_dirty = True
            return
        self._resolve_state()
        around = self._surroundings()
        if len(self._entry_states) > 64:
            self._entry_states.clear()
        resolved = (self._state_base, self._fill, self._point_size, self._blend_on, self._alpha_tested,
                    self._auto_cull, around)  # fmt: skip
        refs = [weakref.ref(above) for above in path]
        self._entry_states[key] = (refs, versions, self._kinds_seen, resolved, leadings)

    def _new_state_kinds(self) -> None:
        """A GL state class was defined since the last compile: items must capture one more value."""
        self._kinds_seen = len(kinds())
        self._states.clear()
        self._node_cache.clear()
        self._compiled = None
        self._entry_states.clear()
        self.state.invalidate()

    def _prune_caches(self) -> None:
        """Drop cache entries of nodes that no longer exist (amortised: when the cache doubled)."""
        if len(self._node_cache) > self._prune_limit:
            self._node_cache = {k: v for k, v in self._node_cache.items() if v.ref() is not None}
            live = set(self._node_cache)
            self._occurrences = {pair: k for pair, k in self._occurrences.items() if k in live}
            self._occurrence_of = {n: found for n, found in self._occurrence_of.items() if found[1]() is not None}
            self._prune_limit = max(4096, 2 * len(self._node_cache))

    # -- what painters call ------------------------------------------------------------
    def submit(
        self,
        geometry: Geometry,
        local: np.ndarray | None = None,
        kind: str | None = None,
        extra: Any = None,
        transparent: bool | None = None,
    ) -> DrawItem:
        """Append a draw item for ``geometry`` in the current state (model matrix, material, GL state).

        ``local`` is a shape-local matrix applied after the model matrix (the
        native painters scale a unit mesh with it).  Painters call this; it
        issues no GL call.
        """
        if self.state.state_dirty or len(self._state_base[0]) != self._kinds_seen:
            if len(kinds()) != self._kinds_seen:
                self._new_state_kinds()
            self._resolve_state()
        if self.state.surface_dirty:
            self._resolve_surface()
        m = self.engine.model_matrix()
        if local is not None:
            m = m @ local
        row = self._surface_row.copy()
        row[_MODEL] = m.T.ravel()
        if kind is None:
            kind = (
                "points"
                if geometry.mode == "triangles" and self._fill == "points"
                else ("mesh" if geometry.mode == "triangles" else geometry.mode)
            )
        app = self._appearance
        if transparent is None:
            transparent = drawn_transparent(app, geometry, self._blend_on, self._alpha_tested)
        cull = None
        single = not app.double_sided and kind == "mesh"
        if (single or (geometry.closed and not transparent)) and kind == "mesh" and self._auto_cull:
            # a closed opaque surface never shows its back faces, a single-sided material hides them: cull them
            # (mirrored instances: the front)
            cull = "back" if _det3(m) > 0.0 else "front"
        state = self._state_for(kind, geometry, extra, cull, int(row[_SHADING_MODEL]))
        item = DrawItem(
            geometry,
            state,
            row,
            transparent,
            self.engine.current_node,
            self._group_path[-1],
            tuple(self.engine.context.mono_stack(Transform)),
            local,
            self._technique_path,
        )
        item.surface = self._surface_entry
        self._scope.entries.append(item)
        return item

    def capture(self, shape: Any) -> list[DrawItem]:
        """The draw items ``shape`` makes in the current state, without drawing them (instance sets use it)."""
        scope = Scope()
        outer = self._scope
        self._scope = scope
        try:
            self.engine.eval(shape)
        finally:
            self._scope = outer
        return scope.all_items()

    def submit_instances(
        self, source: Any, template: DrawItem, matrices: np.ndarray, colors: np.ndarray | None, may_mirror: bool
    ) -> DrawItem:
        """An item drawing ``template`` once per matrix (``(N, 4, 4)``, after the current model matrix).

        ``source`` is the instance set; ``colors`` (``(N, 4)`` display RGBA or
        None) replace the template's colour as ``om.Color`` would.  The rows
        are made with numpy in one go (:func:`~.instancing.instance_rows`);
        the item is drawn as one instanced batch.
        """
        made = instance_rows(
            template.row, template.local, template.transparent, self.engine.model_matrix(), matrices, colors, may_mirror
        )
        item = DrawItem(
            template.geometry,
            self.instance_state(template, made.mirrored),
            template.row,
            made.transparent,
            template.node,
            template.groups,
            template.chain,
            None,
            template.techniques,
        )
        item.instances = made.rows
        item.instance_models = made.models
        item.source = source
        item.template = template
        item.source_colors = _colors_copy(source)
        item.colors_at = source.written_at("colors")
        item.mask_at = (source.written_at("scales"), source.written_at("visible"))
        item.source_mask = mask_copies(source)
        self._scope.entries.append(item)
        return item

    def instance_state(self, template: DrawItem, mirrored: bool) -> DrawState:
        """The template's state, or the same without face culling when some instance mirrors."""
        state = template.state
        if mirrored and not template.transparent and state.value(CullFace) in ("back", "front"):
            # mirrored instances: cull nothing rather than the wrong faces of some
            state = self._state_for(
                state.kind, template.geometry, state.extra, "none", int(template.row[_SHADING_MODEL])
            )
        return state

    def _resolve_state(self) -> None:
        mono = self.engine.mono
        style = mono(DrawStyle)
        self._fill = style.mode if style is not None else "filled"
        # without a DrawStyle: DrawStyle's default (1 px), as in POV-Ray and Mitsuba
        self._point_size = float(style.point_size) if style is not None else _DEFAULT_POINT_SIZE
        values = []
        features: list[tuple[str, Any]] = []
        uniforms: list[tuple[str, Any]] = []
        code: list[Any] = []
        special = False
        cull_set = False
        for k in kinds():
            if issubclass(k, GLState):
                top = mono(k)
                value = top.capture() if top is not None else k.default
                if k is CullFace:
                    cull_set = top is not None
                    if top is None and style is not None:
                        value = style.cull
            elif k is FillMode:
                value = self._fill == "wireframe"
            elif k is LineWidth:
                value = float(style.line_width) if style is not None else 1.0
            elif k.source() is not None:  # a kind capturing a generic attribute (Shadowing, Mirror)
                top = mono(k.source())
                value = k.default if top is None else k.from_attribute(top)
            else:
                value = k.default
            values.append(value)
            if value != k.default:
                special = special or k.orders(value)
                extra = k.features(value)
                if extra:
                    features.extend(extra)
                    uniforms.extend(k.uniforms(value))
                    if k.fragment_code or k.fragment_main:
                        code.append(k)
        raster = tuple(values)
        from .attributes import AlphaTest, Blend

        self._blend_on = raster[Blend.index] is not None
        # an om.gl.AlphaTest cuts out what the alpha hides: such surfaces are drawn (and write depth) as opaque ones
        self._alpha_tested = raster[AlphaTest.index] is not None
        cull_value = raster[CullFace.index]
        # automatic back-face culling only where nothing decides culling and nothing shows the inside
        self._auto_cull = not cull_set and cull_value == "none" and not self.state.clips and self._fill != "wireframe"
        fog = mono(Fog)
        fog_key = None
        if fog is not None:
            fog_key = (
                linear_rgb(fog.color),
                float(fog.start),
                float(fog.end),
                float(fog.density),
                FOG_MODES[fog.mode],
            )
        self._state_base = (
            raster,
            tuple(features),
            tuple(uniforms),
            tuple(code),
            special,
            tuple(plane for _, plane in self.state.clips),
            fog_key,
            mono(LightSwitch),
            style is not None and style.shading == "flat",
        )
        self.state.state_dirty = False

    def _check_texture(self, texture: Any) -> None:
        if getattr(texture, "rendered", False):
            return  # a render texture: its pipeline checks its size when it is made
        checked = self._checked_textures.get(id(texture))
        if checked is not None and checked[0]() is texture and checked[1] == texture.version:
            return
        try:
            h, w = texture.image_array().shape[:2]
        except (OSError, ValueError) as exc:  # a missing or unreadable image file: say where it is used
            where = f" in node {self.engine.node_path}" if self.engine.node_path else ""
            raise type(exc)(
                f"GLEngine: {exc}{where}; fix the path or pass an array (om.Texture(numpy_array))"
            ) from None
        self.engine.check_texture_size(f"Texture (image {w}x{h})", (w, h), self.engine.max_texture_size)
        if len(self._checked_textures) > 4096:
            self._checked_textures.clear()
        self._checked_textures[id(texture)] = (weakref.ref(texture), texture.version)

    def _state_for(self, kind: str, geometry: Geometry, extra: Any, cull_override: str | None, model: int) -> DrawState:
        raster, state_features, uniforms, code, special, clip, fog, switch, flat = self._state_base
        texset = self._texset
        features: list[tuple[str, Any]] = []
        if geometry.colors is not None:
            features.append(("VCOLOR", True))
        textured = bool(texset.textures) and geometry.texcoords is not None and kind == "mesh"
        bound: tuple = ()
        if textured:
            features.append(("UVS", True))
            features.extend(texset.features)
            if texset.uv1 and geometry.texcoords1 is not None:
                features.append(("UV1", True))
            if texset.normal and geometry.tangent_source is not None:
                features.append(("NORMAL_MAP", True))
            uniforms = uniforms + texset.uniforms
            bound = texset.textures
        if kind in ("mesh", "points") and texset.alpha:
            features.extend(texset.alpha)
            uniforms = uniforms + texset.alpha_uniforms
        if flat and kind == "mesh":
            features.append(("FLAT", True))
        if clip:
            features.append(("NCLIP", len(clip)))
        if fog is not None:
            features.append(("FOG", True))
        if kind == "points" and geometry.sizes is not None:
            features.append(("VSIZE", True))
        if kind in ("mesh", "points"):
            features.append(("MODEL", model))
            features.extend(state_features)
        if geometry.program_features:  # geometry drawn by a program of its own (GPU-tessellated NURBS patches)
            features.extend(geometry.program_features)
            uniforms = uniforms + geometry.program_uniforms
        if cull_override is not None:
            raster = raster[: CullFace.index] + (cull_override,) + raster[CullFace.index + 1 :]
        key = (kind, tuple(features), extra, raster, bound, clip, fog, switch, uniforms, code)
        state = self._states.get(key)
        if state is None:
            if len(self._states) > 4096:  # e.g. text labels that change every frame
                self._states.clear()
            state = self._states[key] = DrawState(
                kind,
                tuple(features),
                raster,
                uniforms=uniforms if kind in ("mesh", "points") else (),
                code=code if kind in ("mesh", "points") else (),
                texture=texset.base if textured else None,
                textures=bound,
                clip=clip,
                fog=fog,
                switch=switch,
                extra=extra,
                overlay=kind == "text",
                special=special,
            )
        return state

    def _surroundings(self) -> tuple[Any, ...]:
        """(texture, layers, bump, highlight, material description) in force: read again only when the compile
        state changed otherwise than by its surface stack since they were last read."""
        state = self.state
        if state.changes != self._around_changes:
            mono = self.engine.mono
            description = None if self.description is None else mono(self.description)
            self._around = (mono(Texture), mono(MultiTexture), mono(BumpMap), mono(Highlight), description)
            self._around_changes = state.changes
        return self._around

    def _resolve_surface(self) -> None:
        """The one appearance model (``resolve_appearance``) as an instance row and a texture set."""
        entry = self._surface_entry = self.surface_entry(self.state.surface, self._surroundings())
        app, row, texset, _ = entry
        point_size = self._point_size
        if row[_POINT_SIZE] != point_size:
            row = row.copy()
            row[_POINT_SIZE] = point_size
        self._appearance = app
        self._texset = texset
        self._surface_row = row
        self.state.surface_dirty = False

    def surface_entry(self, stack: Any, context: tuple) -> tuple[Any, np.ndarray, TextureSet, tuple]:
        """The resolved surface of the surface ``stack`` (Material / PBRMaterial / Color, outermost first) in
        ``context`` (the Texture, MultiTexture, BumpMap, Highlight and material description in force, each or
        None): ``(appearance, row of its surface fields, texture set, context)``, memoised by what it reads.

        Draw items keep the entry their row was made from (``DrawItem.surface``): an attribute replaced by one
        of the same role is resolved again from it (:mod:`.dirty`)."""
        texture, layers, bump, highlight, description = context
        top = stack[-1] if stack else None
        plain = top.__class__ is Material and texture is None and layers is None and bump is None
        if plain and highlight is None and description is None:
            # the innermost is a plain Material and nothing else is read: its values decide (a node added per
            # frame with a new Material of the same colour finds the row, ids and texture set made before)
            key: tuple = (Material, top.values())
        else:
            plain = False
            key = (
                appearance_key(stack, texture, layers, bump),
                version_key(highlight),
                version_key(description),
            )
        memo = self._surface_memo
        entry = memo.get(key)
        if entry is not None and plain and entry[0].material is not top:
            # made for another material of these values: the appearance names this one (dirty.py follows it)
            return (decided_by(entry[0], top), *entry[1:])
        if entry is None:
            app = resolve_appearance(stack, texture, layers, bump)
            for tex in app.textures:
                self._check_texture(tex)
            # the attributes are kept alive with the entry, so the ids in its key stay theirs
            # (with the shading model and the id of the material description: the deferred pipeline's table)
            row = self._material_row(
                app, highlight, description, self.engine.material_table.for_appearance(app, description)
            )
            entry = (app, row, texture_set(app), (texture, layers, bump, highlight, description))
            if len(memo) > 256:
                memo.clear()
            memo[key] = entry
        return entry

    def _material_row(self, app: Appearance, highlight: Any, description: Any, material: int) -> np.ndarray:
        """A row holding the surface fields (the model matrix is filled per item); colours are linear;
        ``material``: the id of its material description in the deferred pipeline's table.

        Made from one list of Python floats (one numpy call: a replaced Material makes one per frame)."""
        zeros = _ZEROS4
        model = shading_model(app.model, description)
        if app.model == "pbr":
            alpha = 1.0 if app.alpha_mode != "blend" else app.alpha
            specular, emission, ambient = zeros, (*app.emission, model), zeros
            pbr = (app.roughness, app.metallic, material, 0.0)
        else:
            alpha = app.alpha
            specular, emission, pbr = (*app.specular, app.shininess), (*app.emission, model), (0.0, 0.0, material, 0.0)
            ambient = (*app.ambient, 1.0 if app.ambient_follows_base else 0.0)
        lit = zeros if highlight is None else (*linear_rgb(highlight.color), 1.0)
        # the fields in the row's order (_SURFACE_FIELDS), the model matrix zero
        values = [
            *_ZEROS16,
            *app.base,
            alpha,
            *specular,
            *emission,
            *ambient,
            *pbr,
            *lit,
            _DEFAULT_POINT_SIZE,
            0.0,
            0.0,
            0.0,
        ]
        return np.array(values, np.float32)


def _moves_of(changed: list[Any]) -> tuple[list[Any], list[Any]]:
    """``changed`` split into what the updater applies after a splice (static transforms, translation arrays)
    and the rest; one pass of C-level loops when all of them are moves (a simulation's thousands)."""
    if not changed:
        return [], changed
    classes = set(map(type, changed))
    if all(_is_move(cls) for cls in classes):
        return changed, []
    moves = [c for c in changed if _is_move(c.__class__)]
    return moves, [c for c in changed if not _is_move(c.__class__)]


def _is_move(cls: type) -> bool:
    return cls is TranslationArray or (issubclass(cls, Transform) and cls.static)
