"""Messages put in front of a viser recording, and the player page that plays it so.

A ``.viser`` recording (what viser's scene serializer writes, and what its self-contained page
embeds in base64) is: 8 bytes (little-endian) giving the size of the rest once decompressed, then
zstd of: 8 bytes giving the length ``N`` of a msgpack header, the header (``durationSeconds``,
``messages`` as ``[time, message]`` pairs, ``viserVersion``, ``binaryBufferLengths``), then the
binary buffers the messages point to, each starting on a multiple of 8 bytes counted from the
start of the decompressed data. A header that grows moves the buffers, so they are laid out
again.

Videos use this to draw a recording more cheaply in software WebGL, with nearly the same
picture (:func:`page_for_video`):

- the default lights' shadows off: a recorded scene has no floor, so shadows fall only on the
  exhibit's own small parts (the one to be seen at all is a faint shadow of the bead on the
  tumbling disk's inertia ellipsoid), while the three shadow maps, redrawn for every frame,
  cost a large share of the frame;
- the viewer's default environment map (image-based lighting, which a recording leaves to the
  viewer) replaced by a hemisphere light (:data:`SKY_LIGHT`) of about the same brightness:
  every lit pixel of a mesh samples the environment map several times, a hemisphere light is a
  few operations, and the page no longer prepares the map for seconds before its first frame.
  The exhibits' colours move by a few levels of 255 on average; the hoop's ring loses a little
  of its reflected shading. A recording that sets an environment map of its own (or none)
  keeps it.
"""

from __future__ import annotations

import base64
import re
from typing import Any

_EMBED = re.compile(rb'window\.__VISER_EMBED_DATA__="([A-Za-z0-9+/=]*)"')

NO_SHADOWS: dict[str, Any] = {"type": "EnableLightsMessage", "enabled": True, "cast_shadow": False}
NO_ENVIRONMENT: dict[str, Any] = {
    "type": "EnvironmentMapMessage",
    "hdri_data": None,
    "background": False,
    "background_blurriness": 0.0,
    "background_intensity": 1.0,
    "background_wxyz": [1.0, 0.0, 0.0, 0.0],
    "environment_intensity": 1.0,
    "environment_wxyz": [1.0, 0.0, 0.0, 0.0],
}
# White from above, grey from below, at the intensity whose picture is closest to the default
# environment map's on the helix, the tumbling disk and the hoop, as videos frame them at 960x540
# (mean difference over the exhibits' pixels 4-12 of 255 at 2.5, 5-14 at 3; the helix's 32 at 1).
SKY_LIGHT: dict[str, Any] = {
    "type": "HemisphereLightMessage",
    "name": "/video_sky_light",
    "owner": "",
    "virtual": False,
    "props": {"sky_color": [255, 255, 255], "ground_color": [120, 120, 120], "intensity": 2.5},
}


def _offsets(lengths: list[int], start: int) -> list[int]:
    """Where each binary buffer starts, the first at or after ``start``, each 8-byte aligned."""
    out, offset = [], start
    for n in lengths:
        offset += (8 - offset % 8) % 8
        out.append(offset)
        offset += n
    return out


def read(viser_bytes: bytes) -> tuple[dict[str, Any], list[bytes]]:
    """The header of a ``.viser`` recording and its binary buffers, in order. ``ValueError`` if
    it is not a recording."""
    import msgspec
    import zstandard

    try:
        size = int.from_bytes(viser_bytes[:8], "little")
        inner = zstandard.ZstdDecompressor().decompress(viser_bytes[8:], max_output_size=size)
        n = int.from_bytes(inner[:8], "little")
        head = msgspec.msgpack.decode(inner[8 : 8 + n])
        lengths = [int(x) for x in head.get("binaryBufferLengths") or []]
        buffers = [inner[o : o + m] for o, m in zip(_offsets(lengths, 8 + n), lengths, strict=True)]
        head["messages"] = list(head["messages"])
    except Exception as exc:  # zstd, msgpack or a missing key: the bytes are not a recording
        raise ValueError(f"not a viser recording ({type(exc).__name__})") from None
    return head, buffers


def _pack(head: dict[str, Any], buffers: list[bytes]) -> bytes:
    """A ``.viser`` recording from its header and binary buffers (the inverse of :func:`read`)."""
    import msgspec
    import zstandard

    header = msgspec.msgpack.encode(head)
    parts = [len(header).to_bytes(8, "little"), header]
    offset = 8 + len(header)
    for buf in buffers:
        pad = (8 - offset % 8) % 8
        parts += [bytes(pad), buf]
        offset += pad + len(buf)
    data = b"".join(parts)
    return len(data).to_bytes(8, "little") + zstandard.ZstdCompressor(level=3).compress(data)


def _put_first(head: dict[str, Any], messages: list[dict[str, Any]]) -> dict[str, Any]:
    """``head`` with ``messages`` played before its first message, at the same time."""
    first = head["messages"][0][0] if head["messages"] else 0.0
    return {**head, "messages": [[first, dict(m)] for m in messages] + head["messages"]}


def _locate(page: bytes) -> re.Match:
    """Where a player page embeds its recording (its base64 is group 1)."""
    m = _EMBED.search(page)
    if m is None:
        raise ValueError("not a viser recording page (no embedded scene data)")
    return m


def recording_of_page(page: bytes) -> bytes:
    """The ``.viser`` bytes embedded in a player page (``ValueError`` if there are none)."""
    return base64.b64decode(_locate(page).group(1))


def _embedded(page: bytes) -> tuple[re.Match, dict[str, Any], list[bytes]]:
    """Where a player page embeds its recording, and the recording's header and buffers."""
    m = _locate(page)
    return (m, *read(base64.b64decode(m.group(1))))


def _sets_environment(head: dict[str, Any]) -> bool:
    return any(msg.get("type") == NO_ENVIRONMENT["type"] for _, msg in head["messages"])


def _with_recording(page: bytes, m: re.Match, viser_bytes: bytes) -> bytes:
    return page[: m.start(1)] + base64.b64encode(viser_bytes) + page[m.end(1) :]


def page_with_messages_first(page: bytes, messages: list[dict[str, Any]]) -> bytes:
    """A viser player page whose embedded recording plays ``messages`` before its first
    message, at the same time. ``ValueError`` if the page embeds no recording."""
    m, head, buffers = _embedded(page)
    return _with_recording(page, m, _pack(_put_first(head, messages), buffers))


def sets_environment(page: bytes) -> bool:
    """Whether the page's recording sets an environment map (or switches it off) itself."""
    return _sets_environment(_embedded(page)[1])


def page_for_video(page: bytes, *, shadows: bool = False, environment: bool = False) -> bytes:
    """The player page as videos draw it (see the module docstring): without the shadow maps
    unless ``shadows``, and, unless ``environment``, with the viewer's default environment map
    replaced by :data:`SKY_LIGHT` when the recording leaves the environment to the viewer.
    The recording is read once. ``ValueError`` if the page embeds no recording."""
    if shadows and environment:
        return page
    m, head, buffers = _embedded(page)
    first = [] if shadows else [NO_SHADOWS]
    if not environment and not _sets_environment(head):
        first += [NO_ENVIRONMENT, SKY_LIGHT]
    if not first:
        return page
    return _with_recording(page, m, _pack(_put_first(head, first), buffers))
