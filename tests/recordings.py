"""Reading ``.viser`` recordings back in the tests: viser's format, decoded (8-byte little-endian
size, then zstd of msgpack: ``{"durationSeconds", "messages": [(t, msg), ...], ...}``)."""

from __future__ import annotations

from typing import Any

import msgspec
import zstandard


def decode_recording(data: bytes) -> dict[str, Any]:
    size = int.from_bytes(data[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=size)
    n = int.from_bytes(inner[:8], "little")
    return msgspec.msgpack.decode(inner[8 : 8 + n])


def frame_times(data: bytes) -> list[float]:
    """Distinct message times in a recording (one per recorded frame)."""
    return sorted({round(t, 9) for t, _ in decode_recording(data)["messages"]})
