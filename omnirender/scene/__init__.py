"""The scene graph: nodes, paths, group masks, pre-evaluation, traces and statistics, snapshots."""

from ..core.mask import MaskError, compile_mask
from .node import Node, Visitor
from .snapshot import SceneMirror, SnapNode, Snapshot, Snapshotter
from .trace import Statistics, TraceEngine, register_statistic, statistics, trace

__all__ = [
    "Node",
    "Visitor",
    "MaskError",
    "compile_mask",
    "TraceEngine",
    "trace",
    "Statistics",
    "statistics",
    "register_statistic",
    "Snapshot",
    "SnapNode",
    "Snapshotter",
    "SceneMirror",
]
