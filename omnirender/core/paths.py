"""The path policy: where a file may make omnirender read other files.

Files are untrusted input.  A scene file, a glTF file (buffers, images), an
OBJ file (``mtllib``, texture maps) or a USD layer names other files, and an
application that renders thumbnails of uploaded models must not be made to
read (and publish, through an export) any file the process can read.  Every
loader therefore resolves the references a file holds with
:func:`resolve_reference`, one rule for all of them:

* a relative reference resolves against the **referencing file's folder** and
  must stay inside it, or inside one of the folders the caller lists in
  ``allowed_roots``, after ``..`` and symbolic links are followed (a link that
  leads out is refused like a ``..`` that does);
* an **absolute path** (``/etc/passwd``, ``C:\\x``, ``\\\\server\\share``) or a
  ``file:`` URI is refused unless it lies inside an allowed root;
* a URI with another scheme (``http:``, ``https:``, ``ftp:``...) is never
  fetched: omnirender does not download (:class:`RemoteReferenceError`);
* ``trusted=True`` lifts the folder rule (the caller vouches for the file's
  author); remote URIs stay refused.

A refusal is an :class:`UntrustedReferenceError` (a ValueError) naming the
referencing file, the reference and the fix: ``trusted=True`` (``--trusted``
on the command line) or ``allowed_roots=[folder]``.  ``data:`` URIs are the
caller's business (they hold the bytes and name no file).

Use :class:`PathPolicy` to carry the caller's choice through a loader::

    policy = PathPolicy(trusted=False, allowed_roots=["/srv/assets"])
    path = policy.resolve("textures/wood.png", referrer="/srv/uploads/chair.gltf", what="images[0].uri")
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import unquote, urlsplit

__all__ = [
    "PathPolicy",
    "UntrustedReferenceError",
    "RemoteReferenceError",
    "resolve_reference",
    "TRUST_FIX",
    "TRUST_FIX_CLI",
]

#: How a caller vouches for a file, in the Python API and on the command line.
TRUST_FIX = (
    "if you trust the file's author, load it with trusted=True, or pass allowed_roots=[folder] to allow the "
    "folder it names"
)
TRUST_FIX_CLI = "if you trust the file's author, run the command again with --trusted"

_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.-]+):")
_WINDOWS_ABSOLUTE = re.compile(r"^(?:[A-Za-z]:[\\/]|[\\/]{2})")


class UntrustedReferenceError(ValueError):
    """A file names another file the path policy does not let it read.

    Attributes: ``referrer`` (the referencing file), ``reference`` (as the
    file wrote it), ``reason`` (why it was refused, without the fix) and
    ``cli_message`` (the same message with the command-line fix).
    """

    def __init__(self, referrer: str, reference: str, reason: str, fix: str = TRUST_FIX) -> None:
        self.referrer = referrer
        self.reference = reference
        self.reason = reason
        super().__init__(f"{referrer}: {reason}; {fix}")
        self.cli_message = f"{referrer}: {reason}; {TRUST_FIX_CLI}" if fix == TRUST_FIX else str(self)


class RemoteReferenceError(UntrustedReferenceError):
    """A file names a URL (``http:``, ``https:``...): omnirender never downloads, trusted or not."""


def _short(text: str, limit: int = 120) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _inside(path: str, root: str) -> bool:
    try:
        return os.path.commonpath([path, root]) == root
    except ValueError:  # different drives on Windows
        return False


@dataclass(frozen=True)
class PathPolicy:
    """What the caller allows a file's references to reach: see the module docs.

    ``trusted`` lifts the folder rule; ``allowed_roots`` lists extra folders
    references may lead into (a shared texture library).  The default policy
    keeps every reference inside the referencing file's folder.
    """

    trusted: bool = False
    allowed_roots: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        roots = self.allowed_roots
        if isinstance(roots, (str, os.PathLike)):
            roots = (roots,)
        if not isinstance(roots, Iterable):
            raise TypeError(f"allowed_roots must be a list of folders, got {type(roots).__name__}")
        clean = []
        for root in roots:
            if not isinstance(root, (str, os.PathLike)):
                raise TypeError(f"allowed_roots must hold folder paths, got {type(root).__name__}")
            clean.append(os.path.realpath(os.path.abspath(os.fspath(root))))
        object.__setattr__(self, "allowed_roots", tuple(clean))
        object.__setattr__(self, "trusted", bool(self.trusted))

    @classmethod
    def of(cls, trusted: bool = False, allowed_roots: Iterable[str | os.PathLike[str]] | None = None) -> PathPolicy:
        """The policy of a loader's ``trusted=`` and ``allowed_roots=`` arguments."""
        return cls(bool(trusted), tuple(allowed_roots or ()))

    def resolve(
        self,
        reference: str,
        referrer: str | os.PathLike[str],
        what: str = "a file",
        *,
        uri: bool = False,
        fix: str = TRUST_FIX,
    ) -> Path:
        """The file ``reference`` names, as written in ``referrer``; :class:`UntrustedReferenceError` if refused.

        ``what`` names the reference in messages (``"images[0].uri"``,
        ``"mtllib"``).  ``uri=True`` reads ``reference`` as a URI (glTF):
        percent-escapes are decoded and ``file:`` URIs become paths.  The
        returned path is absolute; whether the file exists is the caller's
        concern.
        """
        source = os.fspath(referrer)
        if not isinstance(reference, str):
            raise UntrustedReferenceError(
                source, repr(reference), f"{what} must be a file name, got {type(reference).__name__}", fix
            )
        shown = repr(_short(reference))
        if "\x00" in reference:
            raise UntrustedReferenceError(source, reference, f"{what} {shown} holds a NUL character", fix)
        text = reference.strip()
        if not text:
            raise UntrustedReferenceError(source, reference, f"{what} is an empty file name", fix)
        scheme = _SCHEME.match(text)
        if scheme and not _WINDOWS_ABSOLUTE.match(text):
            name = scheme.group(1).lower()
            if name != "file":
                raise RemoteReferenceError(
                    source,
                    reference,
                    f"{what} {shown} is a {name}: URL; omnirender never downloads what a file names",
                    f"download it next to {os.path.basename(source)} and refer to it by a relative path",
                )
            parts = urlsplit(text)
            if parts.netloc not in ("", "localhost"):
                raise RemoteReferenceError(
                    source,
                    reference,
                    f"{what} {shown} names a file on another host ({parts.netloc})",
                    f"copy it next to {os.path.basename(source)} and refer to it by a relative path",
                )
            text = unquote(parts.path)
            if not os.path.isabs(text):
                raise UntrustedReferenceError(source, reference, f"{what} {shown} is a malformed file: URI", fix)
        elif uri:
            text = unquote(text)
            if "\x00" in text:
                raise UntrustedReferenceError(source, reference, f"{what} {shown} holds a NUL character", fix)
        if os.sep != "\\":
            absolute = os.path.isabs(text) or bool(_WINDOWS_ABSOLUTE.match(text))
            text = text.replace("\\", "/")  # files written on Windows separate folders with backslashes
        else:  # pragma: no cover - Windows
            absolute = os.path.isabs(text) or bool(_WINDOWS_ABSOLUTE.match(text))
        folder = os.path.dirname(os.path.abspath(source))
        full = os.path.normpath(text if absolute else os.path.join(folder, text))
        if self.trusted:
            return Path(full)
        real = os.path.realpath(full)
        home = os.path.realpath(folder)
        if absolute:
            if any(_inside(real, root) for root in self.allowed_roots):
                return Path(full)
            raise UntrustedReferenceError(
                source,
                reference,
                f"{what} {shown} is an absolute path; a file may only name files inside its own folder "
                f"({home}) or an allowed root, so that a file from elsewhere cannot read other files on this machine",
                fix,
            )
        if _inside(real, home) or any(_inside(real, root) for root in self.allowed_roots):
            return Path(full)
        how = "leads outside" if not _inside(os.path.normpath(full), folder) else "is a symbolic link leading outside"
        raise UntrustedReferenceError(
            source,
            reference,
            f"{what} {shown} {how} the file's folder ({home}); a file may only name files inside its own folder "
            "or an allowed root, so that a file from elsewhere cannot read other files on this machine",
            fix,
        )


#: The policy of loaders called without ``trusted=`` or ``allowed_roots=``.
DEFAULT_POLICY = PathPolicy()


def resolve_reference(
    reference: str,
    referrer: str | os.PathLike[str],
    what: str = "a file",
    *,
    trusted: bool = False,
    allowed_roots: Iterable[str | os.PathLike[str]] | None = None,
    uri: bool = False,
) -> Path:
    """The file ``reference`` names inside ``referrer``, checked by the path policy (see the module docs).

    Raises :class:`UntrustedReferenceError` (a ValueError) naming ``referrer``,
    the reference and the fix when the reference is an absolute path, a
    ``file:`` URI, leads outside ``referrer``'s folder (``..``, a symbolic
    link) and outside every ``allowed_roots`` folder, unless ``trusted``;
    :class:`RemoteReferenceError` for ``http(s):`` and other URLs, always.
    """
    return PathPolicy.of(trusted, allowed_roots).resolve(reference, referrer, what, uri=uri)
