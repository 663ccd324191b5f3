"""Reading user files as UTF-8 text, with errors that name the file and the place.

Every reader of a user file (PDDL domains and problems, stream files, scene and instance YAML,
plan JSON) reads it through :func:`read_text`: a file that cannot be opened, or whose bytes are
not UTF-8, raises a :class:`~sdar_tamp.errors.SdarError` subclass of the reader's choice instead
of an ``OSError`` or ``UnicodeDecodeError``. A decoding error gives the byte offset of the first
bad byte and its ``line:column`` (columns count characters). A leading UTF-8 byte-order mark is
dropped.
"""

from __future__ import annotations

import codecs
from pathlib import Path
from typing import Protocol

from sdar_tamp.errors import LocatedError, SdarError, SourceLocation


class ErrorFactory(Protocol):
    """Builds a reader's own error: ``detail`` says what is wrong, ``file`` names the file and
    ``location`` is the place in it (``None`` when the file as a whole is the problem)."""

    def __call__(self, detail: str, file: str, location: SourceLocation | None) -> SdarError: ...


class TextFileError(LocatedError):
    """A file that cannot be read or is not UTF-8 text.

    ``file`` is the file name and ``byte_offset`` the offset of the first byte that is not
    UTF-8 (``None`` when the file could not be read at all).
    """

    def __init__(
        self,
        detail: str,
        file: str,
        location: SourceLocation | None = None,
        byte_offset: int | None = None,
    ) -> None:
        self.file = file
        self.byte_offset = byte_offset
        super().__init__(detail if location is not None else f"{file}: {detail}", location)


def read_text(path: str | Path, error: ErrorFactory = TextFileError) -> str:
    """The text of the UTF-8 file at ``path``.

    Raises:
        SdarError: what ``error`` builds (by default :class:`TextFileError`) when the file cannot
            be read (``location`` None) or is not UTF-8 (``location`` at the first bad byte).
    """
    file = str(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise error(f"cannot read file: {exc.strerror or exc}", file, None) from None
    return decode_text(data, file, error)


def decode_text(data: bytes, file: str, error: ErrorFactory = TextFileError) -> str:
    """``data`` decoded as UTF-8 (a leading byte-order mark dropped); ``file`` names it.

    Raises:
        SdarError: what ``error`` builds when ``data`` is not UTF-8.
    """
    skip = len(codecs.BOM_UTF8) if data.startswith(codecs.BOM_UTF8) else 0
    try:
        return data[skip:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = skip + exc.start
        line_start = max(data.rfind(b"\n", 0, offset) + 1, skip)
        # The bytes before the first bad one decode; the mark is no character.
        before = data[line_start:offset].decode("utf-8")
        location = SourceLocation(file, data.count(b"\n", 0, offset) + 1, len(before) + 1)
        detail = (
            f"not UTF-8 text: byte 0x{data[offset]:02x} at byte offset {offset} "
            f"cannot be decoded ({exc.reason}); save the file as UTF-8"
        )
        raised = error(detail, file, location)
        if isinstance(raised, TextFileError):
            raised.byte_offset = offset
        raise raised from None
