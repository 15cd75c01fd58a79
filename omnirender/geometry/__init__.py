"""om.geometry (filled by issue 3)."""

__all__: list[str] = []
