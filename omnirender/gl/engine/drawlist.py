"""The compiled form of a scene: draw items in technique scopes, interned draw states, instanced batches.

Painters do not issue GL calls: they append :class:`DrawItem` objects (a
geometry, a per-instance row in the named layout :data:`~.layout.ROW`, and an
interned :class:`DrawState`).  Items are collected into :class:`Scope`
objects: the root scope holds the scene, and every technique met in a node
opens a nested scope holding what it scopes, so the technique's passes can be
run at draw time on exactly those items.  Opaque items of a scope with the
same geometry and state form one :class:`Batch`, drawn with a single
instanced call; when only some items changed, their rows are rewritten in
place and only that region of the instance buffer is uploaded.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .layout import ROW

__all__ = [
    "DrawItem",
    "DrawState",
    "Batch",
    "Scope",
    "Segment",
    "plan_batches",
    "uniform_material",
    "position_of",
    "drawn_transparent",
]

_MODEL = ROW.slice("model")
_HIGHLIGHT_ON = ROW.at("highlight", "on")
_MATERIAL_COLUMNS = np.concatenate(
    [
        np.arange(ROW.offsets[f.name], ROW.offsets[f.name] + f.size)
        for f in ROW.fields
        if f.name not in ("model", "color")
    ]
)
#: the row fields of the material (all but the model matrix and the colour): a slice when they are one run of
#: columns (every field after the colour: rows[:, _MATERIAL] is then a view, not a gathered copy)
_MATERIAL: slice | np.ndarray = (
    slice(int(_MATERIAL_COLUMNS[0]), int(_MATERIAL_COLUMNS[-1]) + 1)
    if (np.diff(_MATERIAL_COLUMNS) == 1).all()
    else _MATERIAL_COLUMNS
)


class DrawState:
    """Everything but the geometry and the instance row that a draw needs (interned, compared by identity).

    ``raster`` holds one captured value per registered GL state kind
    (:mod:`.state`); ``features`` the program ``#define``s; ``uniforms`` the
    uniform values the state kinds need (e.g. the alpha-test reference);
    ``code`` the state kinds whose GLSL the program includes.
    """

    __slots__ = (
        "kind",
        "features",
        "raster",
        "uniforms",
        "code",
        "texture",
        "textures",
        "clip",
        "fog",
        "switch",
        "extra",
        "overlay",
        "special",
    )

    def __init__(
        self,
        kind: str,
        features: tuple,
        raster: tuple,
        uniforms: tuple = (),
        code: tuple = (),
        texture: Any = None,
        clip: tuple = (),
        textures: tuple = (),
        fog: Any = None,
        switch: Any = None,
        extra: Any = None,
        overlay: bool = False,
        special: bool = False,
    ) -> None:
        self.kind = kind
        self.features = features
        self.raster = raster
        self.uniforms = uniforms
        self.code = code
        #: the base colour texture (or None)
        self.texture = texture
        #: every texture to bind: (sampler uniform, om.Texture, sRGB) triples, in texture-unit order
        self.textures = textures
        self.clip = clip
        self.fog = fog
        self.switch = switch
        self.extra = extra
        self.overlay = overlay
        #: drawing order matters (a state kind says so): batches never merge across this item
        self.special = special

    def value(self, kind: Any) -> Any:
        """The captured value of a state kind (a GL attribute class, e.g. ``om.gl.DepthTest``)."""
        return self.raster[kind.index]

    def __repr__(self) -> str:
        return f"DrawState({self.kind}, {dict(self.features)})"


#: how many places before a hint, and from the end, :func:`position_of` tries before it scans the whole list
_NEAR = 64


def position_of(entries: list[Any], entry: Any, hint: int = -1) -> int:
    """The index of ``entry`` (held once) in ``entries``: near ``hint`` first, then the last places, then a scan
    in C.

    A splice knows where an item probably is: where it was in another list
    kept in the same order, or its batch row (a list only ever loses entries
    before it, so it lies at or a little before the hint); what a splice added
    lies near the end.  Those are a few identity tests instead of a scan over
    the scene.  Draw items and scopes compare by identity.
    """
    n = len(entries)
    if 0 <= hint:
        for i in range(min(hint, n - 1), max(hint - _NEAR, -1), -1):
            if entries[i] is entry:
                return i
    for i in range(n - 1, max(n - 1 - _NEAR, -1), -1):
        if entries[i] is entry:
            return i
    return entries.index(entry)


class DrawItem:
    """One shape occurrence: geometry, state, instance row, transparency, node, tags and techniques of its path."""

    __slots__ = (
        "geometry",
        "state",
        "row",
        "transparent",
        "node",
        "groups",
        "chain",
        "local",
        "slot",
        "techniques",
        "instances",
        "_instance_models",
        "moved_translations",
        "source",
        "template",
        "source_colors",
        "colors_at",
        "mask_at",
        "source_mask",
        "surface",
    )

    def __init__(
        self,
        geometry: Any,
        state: DrawState,
        row: np.ndarray,
        transparent: bool,
        node: Any = None,
        groups: tuple[frozenset[str], ...] = (),
        chain: tuple[Any, ...] = (),
        local: np.ndarray | None = None,
        techniques: tuple[Any, ...] = (),
    ) -> None:
        self.geometry = geometry
        self.state = state
        self.row = row
        self.transparent = transparent
        self.node = node
        #: the group sets of the tagged nodes on the item's path (outermost first), for pass masks
        self.groups = groups
        #: the transforms whose product (then ``local``) is the model matrix, outermost first
        self.chain = chain
        #: the painter's shape-local matrix, or None
        self.local = local
        #: (batch, index) of the item's row in its opaque batch, or None
        self.slot: tuple[Batch, int] | None = None
        #: the techniques whose scopes hold the item (outermost first), for pass predicates
        self.techniques = techniques
        #: for an instance set: its rows (N, ROW.stride), one per instance, drawn as one batch; else None
        self.instances: np.ndarray | None = None
        self._instance_models: np.ndarray | None = None
        #: for an instance set: (N, 3) translations of its positions-only change not yet written into
        #: ``instance_models`` (written when they are next read), or None
        self.moved_translations: np.ndarray | None = None
        #: for an instance set: the InstanceSet and the item of its shape that each instance repeats
        self.source: Any = None
        self.template: DrawItem | None = None
        #: for an instance set: a copy of the colours its rows were made from (None: none), so a frame where
        #: only positions changed writes the translations and keeps the converted colours
        self.source_colors: np.ndarray | None = None
        #: for an instance set: its ``written_at("colors")`` when ``source_colors`` was last found equal to its
        #: colours (a touch naming only other arrays keeps it: the colours are not compared then)
        self.colors_at = -1
        #: for an instance set: its ``written_at`` of its scales and its visibility mask when its rows were made
        #: (while they hold, a touch of the transforms alone moves the rows' translations only)
        self.mask_at: tuple[int, int] = (-1, -1)
        #: for an instance set: copies of the scales and the mask its rows were made with (None where none)
        self.source_mask: tuple[Any, Any] = (None, None)
        #: the compiler's resolved surface the row's surface fields came from (appearance, row, texture set,
        #: context), or None; an attribute replaced by one of the same role is resolved again from it
        self.surface: Any = None

    @property
    def instance_models(self) -> np.ndarray | None:
        """For an instance set: (N, 4, 4) matrices after the chain (instance transform @ local), else None."""
        pending = self.moved_translations
        if pending is not None:
            self.moved_translations = None
            self._instance_models[:, :3, 3] = pending  # type: ignore[index]
        return self._instance_models

    @instance_models.setter
    def instance_models(self, value: np.ndarray | None) -> None:
        self._instance_models = value
        self.moved_translations = None

    def rows(self) -> np.ndarray:
        """The rows this item draws: its instances', or its own as a (1, stride) array.

        An instance set's rows are its batch's rows: translations a move left
        pending there (:meth:`Batch.move_to`) are written first.
        """
        instances = self.instances
        if instances is None:
            return self.row[None, :]
        if self.slot is not None:
            self.slot[0].settle()
        return instances

    def world_bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World-space (min, max) of what the item draws (every instance), or None when it draws nothing."""
        return world_bounds([self])

    @property
    def item_class(self) -> str:
        """``"opaque"``, ``"transparent"`` or ``"overlay"``: which pass of the forward technique draws it."""
        if self.state.overlay:
            return "overlay"
        return "transparent" if self.transparent else "opaque"

    @property
    def path(self) -> str:
        """Path of the node the shape was evaluated in ("" outside any node)."""
        node = self.node
        return "" if node is None else node.path

    def __repr__(self) -> str:
        return f"DrawItem({self.geometry.label}, {self.state.kind}, transparent={self.transparent})"


def drawn_transparent(app: Any, geometry: Any, blend_on: bool, alpha_tested: bool) -> bool:
    """Whether a surface of ``app`` (a resolved ``Appearance``) on ``geometry`` is drawn with the transparent
    items (blended, sorted): under an ``om.gl.Blend``, or see-through and not cut out by an ``om.gl.AlphaTest``."""
    see_through = app.alpha_mode == "blend" or (
        app.alpha_mode == "opaque" and app.model == "phong" and geometry.translucent
    )
    return blend_on or (see_through and not alpha_tested)


def world_bounds(items: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """World-space (min, max) of what ``items`` draw (every instance), or None when they draw nothing.

    The rows are gathered per geometry and each box is transformed at once by
    its centre and half extent (``|M| e``), so a frame of 10,000 items costs a
    few milliseconds, not a matrix product per item.
    """
    by_geometry: dict[int, tuple[Any, list[np.ndarray]]] = {}
    in_batches: dict[int, tuple[Batch, list[int]]] = {}  # items whose row is a batch row: gathered by index
    for item in items:
        slot = item.slot
        if slot is not None and item.instances is None:
            found = in_batches.get(id(slot[0]))
            if found is None:
                found = in_batches[id(slot[0])] = (slot[0], [])
            found[1].append(slot[1])
            continue
        entry = by_geometry.get(id(item.geometry))
        if entry is None:
            entry = by_geometry[id(item.geometry)] = (item.geometry, [])
        entry[1].append(item.rows())
    for batch, picks in in_batches.values():
        entry = by_geometry.get(id(batch.geometry))
        if entry is None:
            entry = by_geometry[id(batch.geometry)] = (batch.geometry, [])
        entry[1].append(batch.rows[picks])
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for geometry, parts in by_geometry.values():
        rows = parts[0] if len(parts) == 1 else np.concatenate(parts)
        if not len(rows):
            continue
        b0, b1 = (np.asarray(b, dtype=np.float64) for b in geometry.bounds)
        models = rows[:, _MODEL].reshape(-1, 4, 4).astype(np.float64)  # each row holds M transposed
        linear = models[:, :3, :3]  # (M^T)[:3, :3]: row j holds column j of M
        center = (b0 + b1) / 2.0 @ linear + models[:, 3, :3]
        half = (b1 - b0) / 2.0 @ np.abs(linear)
        lo = np.minimum(lo, (center - half).min(axis=0))
        hi = np.maximum(hi, (center + half).max(axis=0))
    if not np.all(np.isfinite(lo)):
        return None
    return lo, hi


_ROW_TRANSLATION_COLUMNS = slice(ROW.offsets["model"] + 12, ROW.offsets["model"] + 15)  # rows hold M transposed
_TRIPLE = np.dtype((np.void, 12))
#: a row seen as one record whose field ``t`` is the model matrix's translation (three float32s as 12 bytes):
#: writing (N, 3) float32 translations through it is one copy of N 12-byte items, not N loops of three floats
_ROW_TRANSLATION = np.dtype({"names": ["t"], "formats": [_TRIPLE], "offsets": [(ROW.offsets["model"] + 12) * 4],
                             "itemsize": ROW.stride * 4})  # fmt: skip


def set_translations(rows: np.ndarray, world: np.ndarray) -> None:
    """``rows[:, _TRANSLATION] = world`` for (N, 3) C-contiguous float32 ``world``."""
    if rows.flags.c_contiguous and rows.dtype == np.float32:
        rows.view(_ROW_TRANSLATION)[:, 0]["t"] = world.view(_TRIPLE)[:, 0]
    else:
        rows[:, _ROW_TRANSLATION_COLUMNS] = world


#: (column, floats per record) -> a record of that many float32s seen as one field ``t`` of three at ``column``
_TRIPLE_AT: dict[tuple[int, int], np.dtype] = {}


def scatter_translations(packed: np.ndarray, column: int, places: np.ndarray | slice, rows: np.ndarray) -> None:
    """``packed[places, column:column + 3] = rows[:, _TRANSLATION]``: the translations of ``rows`` (full rows,
    float32) into records ``places`` of ``packed`` (float32, the buffer's layout), each moved as 12 bytes
    rather than three strided floats (a sorted batch's moved rows lie anywhere in its buffer)."""
    if not (
        packed.flags.c_contiguous
        and packed.dtype == np.float32
        and packed.ndim == 2
        and rows.flags.c_contiguous
        and rows.dtype == np.float32
    ):
        packed[places, column : column + 3] = rows[:, _ROW_TRANSLATION_COLUMNS]
        return
    key = (column, packed.shape[1])
    record = _TRIPLE_AT.get(key)
    if record is None:
        record = _TRIPLE_AT[key] = np.dtype(
            {"names": ["t"], "formats": [_TRIPLE], "offsets": [column * 4], "itemsize": packed.shape[1] * 4}
        )
    packed.view(record)[:, 0]["t"][places] = rows.view(_ROW_TRANSLATION)[:, 0]["t"]


class Batch:
    """Opaque items sharing geometry and state, drawn with one instanced call.

    ``rows`` are the items' full rows; the GPU buffer holds only the fields
    of ``layout`` (what the batch's program variants read), re-packed when a
    variant needs more.
    """

    __slots__ = (
        "geometry",
        "state",
        "items",
        "_rows",
        "_pending",
        "highlight_seen",
        "buffer",
        "layout",
        "vaos",
        "capacity",
        "_dirty",
        "moved_range",
        "packed",
        "uniform",
        "sorted_for",
        "position",
        "places",
        "drawn",
        "version",
        "source",
        "picks",
        "source_version",
        "storage",
        "sparse",
        "log",
        "inverse",
        "offsets",
        "moved_offsets",
        "offset_order",
        "depth_order",
    )

    def __init__(self, geometry: Any, state: DrawState) -> None:
        self.geometry = geometry
        self.state = state
        self.items: list[DrawItem] = []
        self._rows = np.empty((0, ROW.stride), np.float32)
        #: (N, 3) float32 world translations of every row not yet written into them (:meth:`move_to`), or None
        self._pending: np.ndarray | None = None
        #: (version, whether some row is highlighted) as last seen; kept by moves (translations only)
        self.highlight_seen: tuple[int, bool] | None = None
        self.buffer: Any = None
        self.layout: Any = None
        #: vertex arrays per program
        self.vaos: dict[int, Any] = {}
        self.capacity = 0
        self._dirty: tuple[int, int] | None = None
        #: (version, lo, hi) when every change since the last upload was to the rows' translations only
        #: (:meth:`moved`): the upload then rewrites only those columns of ``packed``; any other change clears it
        self.moved_range: tuple[int, int, int] | None = None
        #: the GPU buffer's content, rows in buffer order restricted to ``layout`` (kept by the drawer), or None
        self.packed: np.ndarray | None = None
        #: True when every instance has the same material apart from its colour (uniforms instead of attributes)
        self.uniform = False
        #: the view (bytes of the view matrix) the instances were last sorted front to back for, or None
        self.sorted_for: bytes | None = None
        #: when sorted: the GPU buffer position of each row (so changed rows are rewritten where they lie)
        self.position: np.ndarray | None = None
        #: the row at each GPU buffer place (``position``'s inverse) when known, kept by row edits; checked
        #: against ``position`` before use (the drawer may sort again without it)
        self.places: np.ndarray | None = None
        #: how many instances (from the start of the buffer) the frame's own view sees (the rest are culled)
        self.drawn = 0
        #: counts changes of ``rows`` (batches filtered from this one follow it)
        self.version = 0
        #: a filtered batch: the batch it selects from, the rows it selects (None: all) and that batch's version
        self.source: Batch | None = None
        self.picks: np.ndarray | None = None
        self.source_version = -1
        #: the array ``rows`` is the start of (spare rows after it, so a row appended keeps every item's view)
        self.storage: np.ndarray | None = None
        #: rows changed since the last upload when few (uploaded one by one), or None: the ``dirty`` range
        self.sparse: list[int] | None = None
        #: the last row changes as (version after, lo, hi), so filtered batches copy only those rows
        self.log: list[tuple[int, int, int]] = []
        #: a filtered batch: (picks, source row -> index here or -1), made when first needed
        self.inverse: tuple[Any, np.ndarray] | None = None
        #: an instance set's batch: the GPU buffer of its (N, 3) float32 world translations in row order (the
        #: shader's ``i_offset``, replacing ``i_model``'s), so moving the instances uploads only them; else None
        self.offsets: Any = None
        #: (version, (N, 3) float32 contiguous world translations) written with :meth:`moved` by an instance
        #: set's positions-only change: the drawer uploads it as it is while ``moved_range`` is that version's
        self.moved_offsets: tuple[int, np.ndarray] | None = None
        #: an instance set's batch: the row drawn at each place of its buffers (visible ones first), None: row order
        self.offset_order: np.ndarray | None = None
        #: an instance set's batch: (view key, every row front to back for that view, ``version`` then) as last
        #: sorted; kept across moves (culling again partitions it), made again when the view or the count
        #: changes, and after ``drawer.RESORT_AFTER`` changes
        self.depth_order: tuple[Any, np.ndarray, int] | None = None

    @property
    def rows(self) -> np.ndarray:
        """The items' full rows, (N, ROW.stride) float32 (translations a move left pending are written first)."""
        if self._pending is not None:
            self.settle()
        return self._rows

    @rows.setter
    def rows(self, value: np.ndarray) -> None:
        self._rows = value
        self._pending = None  # new rows: translations pending for the old ones do not apply
        self.highlight_seen = None

    @property
    def size(self) -> int:
        """How many rows (read without writing pending translations)."""
        return len(self._rows)

    def holds(self, rows: np.ndarray) -> bool:
        """Whether ``rows`` is this batch's rows array itself (an instance set's batch holds its item's)."""
        return self._rows is rows

    def first_row(self) -> np.ndarray:
        """Row 0 for its material fields (a pending move is not written: translations are not read here)."""
        return self._rows[0]

    def settle(self) -> None:
        """Write the translations :meth:`move_to` left pending into the rows."""
        pending = self._pending
        if pending is not None:
            self._pending = None
            set_translations(self._rows, pending)

    def move_to(self, world: np.ndarray) -> None:
        """Every row's translation becomes ``world`` ((N, 3) C-contiguous float32, not written to afterwards).

        An instance set's positions-only move: the translations are written into
        the rows only when the rows are next read (:attr:`rows`), so a frame that
        just draws the set uploads ``world`` (``moved_offsets``) and never touches
        the rows (a strided write over all of them: 0.25-1 ms per 100,000).
        """
        self._pending = world
        n = len(world)
        # self.moved(0, n) written out (a frame's few Python calls count: every row moved, one range)
        d = self._dirty
        only = self.moved_range is not None or (d is None and not self.sparse)
        version = self.version
        seen = self.highlight_seen
        if seen is not None and seen[0] == version:
            self.highlight_seen = (version + 1, seen[1])  # translations change no highlight
        self.version = version = version + 1
        log = self.log
        log.append((version, 0, n))
        if len(log) > 32:
            del log[:16]
        self.sparse = None
        self._dirty = d = (0, n) if d is None else (min(d[0], 0), max(d[1], n))
        self.moved_range = (version, *d) if only else None
        self.moved_offsets = (version, world)

    def hold(self, rows: np.ndarray) -> None:
        """Take ``rows`` (N, stride) into storage with spare rows; the items' rows become views of them."""
        n = len(rows)
        storage = np.empty((n + max(16, n // 8), ROW.stride), np.float32)
        storage[:n] = rows
        self.storage = storage
        self.rows = storage[:n]
        for i, item in enumerate(self.items):
            item.row = storage[i]

    def append_row(self, item: DrawItem) -> int:
        """Add ``item`` as the last row (its row becomes a view of it); returns the row's index."""
        seen = self._highlight_now()
        n = len(self.rows)
        storage = self.storage
        if storage is None or n == len(storage):
            self.items.append(item)
            self.hold(np.concatenate([self.rows, item.row[None, :]]))
        else:
            storage[n] = item.row
            self.rows = storage[: n + 1]
            self.items.append(item)
            item.row = storage[n]
        item.slot = (self, n)
        if self.uniform and n:
            rows = self._rows
            if rows[0, _MATERIAL].tolist() != rows[n, _MATERIAL].tolist():  # (Python floats: few, compared at once)
                self.uniform = False
        if self.position is not None:
            if self.drawn == n:  # everything in view: the new row is drawn from the end of the buffer
                self.position = _appended_place(self.position, n)
                if self.places is not None and len(self.places) == n:
                    self.places = _appended_place(self.places, n)
                self.drawn = n + 1
            else:
                self.position = None  # culled: sorted and culled again
        self.row_changed(n)
        if seen is not None:  # whether some row is highlighted: the answer before, or the new row's
            self.highlight_seen = (self.version, seen or float(self._rows[n, _HIGHLIGHT_ON]) > 0.0)
        return n

    def remove_row(self, index: int) -> int | None:
        """Remove row ``index``: the last row moves into its place; returns the moved row's old index (or None).

        The removed item keeps a copy of its row; the moved item's slot and
        row view follow it.  In the GPU buffer the row drawn last takes the
        removed row's place (sorted batches), so one row is uploaded.
        """
        seen = self._highlight_now()
        last = len(self.rows) - 1
        removed = self.items[index]
        removed.row = removed.row.copy()
        removed.slot = None
        storage = self.storage if self.storage is not None else self.rows
        moved: int | None = None
        if index != last:
            storage[index] = storage[last]
            item = self.items[last]
            self.items[index] = item
            item.slot = (self, index)
            item.row = storage[index]
            moved = last
        self.items.pop()
        self.rows = storage[:last]
        position = self.position
        if position is not None:
            if self.drawn < last + 1:
                self.position = None
            else:
                freed = int(position[index])
                tail, places = self._row_at(last)  # the row in the buffer's last place
                if moved is not None:
                    position[index] = position[last]
                    if places is not None:
                        places[position[index]] = index
                    if tail == last:
                        tail = index
                position = position[:last]  # a view: an appended row takes the spare place after it
                if freed != last:
                    position[tail] = freed  # the row drawn last fills the freed place
                    if places is not None:
                        places[freed] = tail
                    self.row_changed(tail)
                self.position = position
                self.places = None if places is None else places[:last]
                self.drawn = last
        if moved is not None and self.position is None:
            self.row_changed(index)
        if self.sparse is not None:
            self.sparse = [i for i in self.sparse if i < last]
        self.version += 1
        if seen is False:  # no row was highlighted: none is (one that was may have left: asked again)
            self.highlight_seen = (self.version, False)
        return moved

    def _highlight_now(self) -> bool | None:
        """Whether some row is highlighted, as last seen while it holds (``highlight_seen``), else None."""
        seen = self.highlight_seen
        return seen[1] if seen is not None and seen[0] == self.version else None

    def _row_at(self, place: int) -> tuple[int, np.ndarray | None]:
        """The row drawn at buffer ``place`` and the inverse of ``position`` (made here once, then kept by the row
        edits; made again when it does not answer ``position``: the drawer sorted the rows again)."""
        position = self.position
        assert position is not None
        places = self.places
        if places is not None and len(places) == len(position):
            row = int(places[place])
            if position[row] == place:
                return row, places
        places = np.empty(len(position), position.dtype)
        places[position] = np.arange(len(position))
        self.places = places
        return int(places[place]), places

    def row_changed(self, index: int) -> None:
        """Row ``index`` must be uploaded (kept as a sparse list while short, else as the dirty range)."""
        self.moved_range = None
        sparse = self.sparse
        if sparse is None and self._dirty is None:
            self.sparse = [index]
        elif sparse is not None and len(sparse) < 32:
            sparse.append(index)
        else:
            self.version += 1
            self._log(index, index + 1)
            self.version -= 1  # changed() below counts the change
            if self.sparse:
                lo, hi = min(self.sparse), max(self.sparse) + 1
                self.dirty = (lo, hi) if self.dirty is None else (min(self.dirty[0], lo), max(self.dirty[1], hi))
                self.sparse = None
            self.changed(index, index + 1)
            return
        self.version += 1
        self._log(index, index + 1)

    def row_moved(self, index: int) -> None:
        """Row ``index``'s model matrix alone changed (a move): :meth:`row_changed`, and the answer to whether
        some row is highlighted holds (``highlight_seen``: the drawer does not read every row again)."""
        seen = self.highlight_seen
        self.row_changed(index)
        if seen is not None and seen[0] == self.version - 1:
            self.highlight_seen = (self.version, seen[1])

    def row_restyled(self, index: int, highlight: bool) -> None:
        """Row ``index``'s surface fields changed (a replaced ``Material``): :meth:`row_changed`; whether some row
        is highlighted holds as for a move unless ``highlight`` (the row's own highlight changed)."""
        if highlight:
            self.row_changed(index)
        else:
            self.row_moved(index)

    def mark(self, index: int) -> None:
        """Row ``index`` changed."""
        self.changed(index, index + 1)

    @property
    def dirty(self) -> tuple[int, int] | None:
        """The range of rows to upload with the next draw, or None."""
        return self._dirty

    @dirty.setter
    def dirty(self, value: tuple[int, int] | None) -> None:
        self._dirty = value
        self.moved_range = None  # set from outside: nothing is known about which columns changed

    def moved(self, lo: int, hi: int) -> None:
        """Rows ``lo:hi`` changed in their translation columns only (positions moved): :meth:`changed`, and the
        upload rewrites only those columns when nothing else changed since the last one."""
        only = self.moved_range is not None or (self._dirty is None and not self.sparse)
        seen = self.highlight_seen
        if seen is not None and seen[0] == self.version:
            self.highlight_seen = (self.version + 1, seen[1])  # translations change no highlight
        self.changed(lo, hi)
        if only:
            lo, hi = self._dirty  # type: ignore[misc]
            self.moved_range = (self.version, lo, hi)

    def changed(self, lo: int, hi: int) -> None:
        """Rows ``lo:hi`` changed: upload them with the next draw, and refresh the batches filtered from this one."""
        d = self._dirty
        self.version += 1
        self._log(lo, hi)
        if self.sparse:
            lo, hi = min(lo, *self.sparse), max(hi, max(self.sparse) + 1)
        self.sparse = None
        self.dirty = (lo, hi) if d is None else (min(d[0], lo), max(d[1], hi))  # (clears moved_range)

    def _log(self, lo: int, hi: int) -> None:
        log = self.log
        log.append((self.version, lo, hi))
        if len(log) > 32:
            del log[:16]

    def follow(self) -> None:
        """A filtered batch: take its source's rows again when they changed since the last time."""
        source = self.source
        if source is None or self.source_version == source.version:
            return
        if self._follow_moved(source) or self._follow_rows(source):
            self.source_version = source.version
            return
        self.rows = source.rows.copy() if self.picks is None else source.rows[self.picks]
        self.dirty = (0, len(self.rows)) if len(self.rows) else None
        self.uniform = uniform_material(self.rows)
        if self.position is not None and len(self.position) != len(self.rows):
            self.position = None
        self.source_version = source.version

    def _follow_moved(self, source: Batch) -> bool:
        """An instance set's batch whose only change since the last follow moved its positions: take the
        translations (as ``moved_offsets`` too, so the upload writes only them); False otherwise."""
        moved = source.moved_offsets
        mr = source.moved_range
        if moved is None or mr is None or not moved[0] == mr[0] == source.version == self.source_version + 1:
            return False
        world = moved[1] if self.picks is None else moved[1][self.picks]
        if len(world) != len(self._rows) or (self._dirty is not None or self.sparse) and self.moved_range is None:
            return False
        self.move_to(world)
        return True

    def _follow_rows(self, source: Batch) -> bool:
        """Copy only the source rows its log says changed since the last follow; False when it cannot say."""
        since = self.source_version
        entries = [e for e in source.log if e[0] > since]
        if since < 0 or len(entries) != source.version - since or not entries:
            return False
        picks = self.picks
        if len(self.rows) != (len(source.rows) if picks is None else len(picks)):
            return False
        inverse = None
        if picks is not None:
            if self.inverse is None or self.inverse[0] is not picks or len(self.inverse[1]) != len(source.rows):
                table = np.full(len(source.rows), -1, np.int64)
                table[picks] = np.arange(len(picks))
                self.inverse = (picks, table)
            inverse = self.inverse[1]
        for _, lo, hi in entries:
            if inverse is None:
                self.rows[lo:hi] = source.rows[lo:hi]
                mine = range(lo, hi)
            else:
                sel = inverse[lo:hi]
                sel = sel[sel >= 0]
                if not len(sel):
                    continue
                self.rows[sel] = source.rows[picks[sel]]
                mine = sel.tolist()
            if len(mine) <= 8:
                for i in mine:
                    self.row_changed(int(i))
            else:
                self.changed(int(min(mine)), int(max(mine)) + 1)
            if self.uniform and len(self.rows) > 1:
                if lo == 0 or (inverse is not None and 0 in mine):
                    self.uniform = uniform_material(self.rows)
                else:
                    check = self.rows[lo:hi] if inverse is None else self.rows[sel]
                    self.uniform = bool((check[:, _MATERIAL] == self.rows[0, _MATERIAL]).all())
        return True

    def release(self) -> None:
        for vao in self.vaos.values():
            vao.release()
        self.vaos.clear()
        if self.buffer is not None:
            self.buffer.release()
            self.buffer = None
        if self.offsets is not None:
            self.offsets.release()
            self.offsets = None
        self.capacity = 0
        self.layout = None
        self.packed = None


def _appended_place(position: np.ndarray, value: int) -> np.ndarray:
    """``np.append(position, value)``, written into the spare place after ``position`` when its storage has one.

    ``position`` is an array of its own or a prefix ``store[:n]`` of the storage this made (the only views of
    it a batch keeps: :meth:`Batch.remove_row` shortens it the same way).
    """
    n = len(position)
    base = position.base
    if isinstance(base, np.ndarray) and base.ndim == 1 and base.dtype == position.dtype and len(base) > n:
        out = base[: n + 1]
    else:
        out = np.empty(n + n // 8 + 16, position.dtype)[: n + 1]
        out[:n] = position
    out[n] = value
    return out


def uniform_material(rows: np.ndarray) -> bool:
    """Whether all rows share every field but the model matrix and the colour."""
    if len(rows) <= 1:
        return True
    tail = rows[:, _MATERIAL]
    return bool((tail == tail[0]).all())


def plan_batches(items: list[DrawItem]) -> tuple[dict[tuple, list[DrawItem]], list[tuple | None]]:
    """Group opaque items by (geometry, state); returns the groups and per-item (key, index) slots.

    Items with special raster state (a state kind whose value makes order
    matter: stencil, colour mask, depth function or mask) are grouped only with
    consecutive items of the same state, so two stencil-writing or masking
    items are never merged across each other and their relative order is
    kept.  Plain items are merged freely within a stretch between special
    items (a batch draws at the position of its first item), never across a
    special item.  Transparent and overlay items get the slot None.
    """
    groups: dict[tuple, list[DrawItem]] = {}
    slots: list[tuple | None] = []
    segment = 0
    previous: DrawState | None = None
    for item in items:
        state = item.state
        if item.transparent or state.overlay:
            slots.append(None)
            continue
        if state is not previous and (state.special or (previous is not None and previous.special)):
            segment += 1
        previous = state
        # an instance set is its own batch (its rows are the application's array); plain items merge
        key = (item.geometry, state, segment) if item.instances is None else (item.geometry, state, segment, id(item))
        group = groups.get(key)
        if group is None:
            group = groups[key] = []
        slots.append((key, len(group)))
        group.append(item)
    return groups, slots


class Segment:
    """A run of a scope's items between nested scopes: its opaque batches and its other items."""

    __slots__ = ("items", "batches", "slots", "others")

    def __init__(self, items: list[DrawItem]) -> None:
        self.items = items
        self.batches: list[Batch] = []
        #: per item of ``items``: (batch, index in batch) or None (transparent, overlay)
        self.slots: list[tuple[Batch, int] | None] = []
        self.others: list[DrawItem] = [it for it in items if it.transparent or it.state.overlay]


class Scope:
    """The draw items a technique scopes (the root scope: the whole scene), in compile order.

    ``entries`` interleaves items and nested scopes as the traversal met them.
    ``plan()`` splits them into :class:`Segment` objects and nested scopes.
    ``technique`` is None for the root (the engine's technique draws it).
    """

    __slots__ = ("technique", "entries", "parts", "positions", "filtered", "__weakref__")

    def __init__(self, technique: Any = None) -> None:
        self.technique = technique
        self.entries: list[DrawItem | Scope] = []
        #: Segment or Scope objects in order (made by plan)
        self.parts: list[Segment | Scope] | None = None
        #: entry index -> (segment, position) of the items (made on the first in-place update)
        self.positions: dict[int, tuple[Segment, int]] | None = None
        #: batches of filtered selections (a pass mask or predicate), by filter key
        self.filtered: dict[Any, Any] = {}

    def items(self) -> list[DrawItem]:
        """This scope's own items, in order."""
        return [e for e in self.entries if isinstance(e, DrawItem)]

    def scopes(self) -> list[Scope]:
        """The nested scopes, in order (from the plan when there is one: a few parts, not every item)."""
        source = self.entries if self.parts is None else self.parts
        return [e for e in source if isinstance(e, Scope)]

    def walk(self) -> list[Scope]:
        """This scope and every scope below it, depth first."""
        out, stack = [], [self]
        while stack:
            scope = stack.pop()
            out.append(scope)
            stack.extend(reversed(scope.scopes()))
        return out

    def all_items(self) -> list[DrawItem]:
        """Every item of this scope and the scopes below it, in compile order."""
        out: list[DrawItem] = []
        stack: list[Any] = [iter(self.entries)]
        while stack:
            for entry in stack[-1]:
                if isinstance(entry, Scope):
                    stack.append(iter(entry.entries))
                    break
                out.append(entry)
            else:
                stack.pop()
        return out

    def shape(self) -> tuple:
        """The structure (technique identities and per-item geometry, state, transparency) for in-place updates."""
        out: list[Any] = [id(self.technique)]
        for e in self.entries:
            if isinstance(e, Scope):
                out.append(e.shape())
            else:
                out.append((id(e.geometry), id(e.state), e.transparent))
        return tuple(out)

    def __repr__(self) -> str:
        name = "root" if self.technique is None else type(self.technique).__name__
        return f"Scope({name}, {len(self.items())} items, {len(self.scopes())} scopes)"
