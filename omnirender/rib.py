"""``om.rib``: RenderMan-specific attributes (the RIB exporter lives in :mod:`omnirender.export.rib`)."""

from .export.rib import Surface

__all__ = ["Surface"]
