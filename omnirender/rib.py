"""``om.rib``: RenderMan-specific attributes (the RIB exporter lives in :mod:`omnirender.formats.rib`)."""

from .formats.rib import Surface

__all__ = ["Surface"]
