"""Reading the user's input files (design files, sweep specs): bounded and regular only.

The reader is ``geometry.reading`` (the bottom layer, so the material loaders use the same
one): a regular file only (a FIFO, a device such as /dev/zero, a socket or a directory is
refused by name), at most ``MAX_INPUT_BYTES``, UTF-8, nested at most ``MAX_DEPTH`` deep;
every refusal is one ParameterError naming the file. This module re-exports it for the
application and holds the TOML writer (``toml_value``).
"""

from __future__ import annotations

import math
from typing import Any

from geometry.reading import (
    MAX_DEPTH,
    MAX_INPUT_BYTES,
    check_depth,
    check_regular,
    read_bytes,
    read_json,
    read_text,
    read_toml,
)

__all__ = ["MAX_DEPTH", "MAX_INPUT_BYTES", "check_depth", "check_regular", "read_bytes",
           "read_json", "read_text", "read_toml", "toml_value"]  # fmt: skip


#: TOML basic-string escapes; other control characters as \uXXXX (TOML 1.0 §String).
_ESCAPES = {"\\": "\\\\", '"': '\\"', "\b": "\\b", "\t": "\\t", "\n": "\\n",
            "\f": "\\f", "\r": "\\r"}  # fmt: skip


def toml_value(v: Any) -> str:
    """``v`` (a string, bool, int or float) as a TOML value: a basic string with its
    control characters escaped, ``inf`` as TOML's inf; what ``design_to_toml`` and
    ``uncertainty.measured_to_toml`` write."""
    if isinstance(v, str):
        out = []
        for ch in v:
            code = ord(ch)
            if ch in _ESCAPES:
                out.append(_ESCAPES[ch])
            elif code < 0x20 or code == 0x7F:
                out.append(f"\\u{code:04X}")
            elif 0xD800 <= code <= 0xDFFF:  # a lone surrogate (an undecodable file name)
                out.append("\\uFFFD")
            else:
                out.append(ch)
        return '"' + "".join(out) + '"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    f = float(v)
    if math.isinf(f):
        return "inf" if f > 0 else "-inf"
    return repr(f)
