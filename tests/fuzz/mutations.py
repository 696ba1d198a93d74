"""Ways to damage an input file, each a pure function of (bytes, random generator) -> bytes.

Byte-level damage applies to every file; structure-aware damage edits what the file means: glTF
JSON (a GLB's JSON chunk too) gets huge counts and lengths, deleted fields and values of the wrong
kind; text formats (TOML scenes, OBJ, MTL, ASCII PLY) get lines deleted or duplicated and numbers
replaced by extreme ones.
"""
from __future__ import annotations

import json
import re
import struct

import numpy as np

# Numbers a damaged file might hold: huge, negative, beyond f32, not finite, off by one.
EXTREME_NUMBERS = ("0", "-1", "1e39", "-1e39", "1e308", "nan", "inf", "4294967296", "2147483648",
                   "99999999999999999999", "0.0000001", "65536", "100000")
HUGE_COUNTS = (2 ** 31, 2 ** 32 - 1, 10 ** 9, 4 * 10 ** 8, 10 ** 12, -1, 0)
# glTF fields whose values size an allocation or a read.
SIZING_FIELDS = ("count", "byteLength", "byteOffset", "byteStride")


# --- bytes ----------------------------------------------------------------------------------------


def truncate(data: bytes, rng: np.random.Generator) -> bytes:
    return data[:int(rng.integers(0, max(1, len(data))))]


def flip_bytes(data: bytes, rng: np.random.Generator) -> bytes:
    if not data:
        return data
    out = bytearray(data)
    for _ in range(int(rng.integers(1, 9))):
        out[int(rng.integers(0, len(out)))] = int(rng.integers(0, 256))
    return bytes(out)


def repeat_chunk(data: bytes, rng: np.random.Generator) -> bytes:
    if not data:
        return data
    start = int(rng.integers(0, len(data)))
    end = min(len(data), start + int(rng.integers(1, 256)))
    return data[:end] + data[start:end] * int(rng.integers(1, 4)) + data[end:]


BYTE_MUTATIONS = (truncate, flip_bytes, repeat_chunk)


# --- glTF JSON ------------------------------------------------------------------------------------


def _paths(value, prefix=()):
    """Every (path, leaf or container) in a JSON document."""
    yield prefix, value
    if isinstance(value, dict):
        for key, item in value.items():
            yield from _paths(item, prefix + (key,))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            yield from _paths(item, prefix + (index,))


def _set(doc, path, value):
    target = doc
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value


def _delete(doc, path):
    target = doc
    for key in path[:-1]:
        target = target[key]
    del target[path[-1]]


def huge_count(doc: dict, rng: np.random.Generator) -> None:
    """A count, length, offset or stride set to a huge (or negative) number."""
    places = [p for p, _ in _paths(doc) if p and p[-1] in SIZING_FIELDS]
    if places:
        _set(doc, places[int(rng.integers(0, len(places)))], int(rng.choice(HUGE_COUNTS)))


def delete_field(doc: dict, rng: np.random.Generator) -> None:
    places = [p for p, _ in _paths(doc) if p and isinstance(p[-1], str)]
    if places:
        _delete(doc, places[int(rng.integers(0, len(places)))])


def wrong_value(doc: dict, rng: np.random.Generator) -> None:
    """A leaf replaced by a value of another kind, a huge index, a non-finite number or a
    nested structure."""
    places = [p for p, v in _paths(doc) if p and not isinstance(v, (dict, list))]
    if not places:
        return
    choices = (None, "x", -1, 10 ** 6, 2 ** 40, 1.5, float("nan"), float("inf"), 1e39, True, [], {},
               [[[[0]]]], "../../../../etc/passwd", "/etc/hostname")
    _set(doc, places[int(rng.integers(0, len(places)))], choices[int(rng.integers(0, len(choices)))])


JSON_MUTATIONS = (huge_count, delete_field, wrong_value)


def mutate_json_text(text: bytes, rng: np.random.Generator) -> bytes:
    doc = json.loads(text)
    for _ in range(int(rng.integers(1, 4))):
        JSON_MUTATIONS[int(rng.integers(0, len(JSON_MUTATIONS)))](doc, rng)
    return json.dumps(doc).encode("utf-8")  # NaN and Infinity stay as Python's json writes them


def mutate_glb(data: bytes, rng: np.random.Generator) -> bytes:
    """A GLB with its JSON chunk mutated and its container lengths kept consistent."""
    json_length = struct.unpack_from("<I", data, 12)[0]
    text = mutate_json_text(data[20:20 + json_length], rng)
    text += b" " * (-len(text) % 4)
    rest = data[20 + json_length:]
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + rest
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


# --- text formats -----------------------------------------------------------------------------------


_NUMBER = re.compile(rb"(?<![\w.])-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def extreme_number(data: bytes, rng: np.random.Generator) -> bytes:
    numbers = list(_NUMBER.finditer(data))
    if not numbers:
        return data
    match = numbers[int(rng.integers(0, len(numbers)))]
    value = EXTREME_NUMBERS[int(rng.integers(0, len(EXTREME_NUMBERS)))].encode()
    return data[:match.start()] + value + data[match.end():]


def delete_line(data: bytes, rng: np.random.Generator) -> bytes:
    lines = data.splitlines(keepends=True)
    if lines:
        del lines[int(rng.integers(0, len(lines)))]
    return b"".join(lines)


def duplicate_line(data: bytes, rng: np.random.Generator) -> bytes:
    lines = data.splitlines(keepends=True)
    if lines:
        i = int(rng.integers(0, len(lines)))
        lines.insert(i, lines[i])
    return b"".join(lines)


TEXT_MUTATIONS = (extreme_number, extreme_number, delete_line, duplicate_line)


def mutate_text(data: bytes, rng: np.random.Generator) -> bytes:
    return TEXT_MUTATIONS[int(rng.integers(0, len(TEXT_MUTATIONS)))](data, rng)


def mutate(name: str, data: bytes, rng: np.random.Generator) -> tuple[bytes, str]:
    """A damaged copy of the file `name` holding `data`, and what was done to it."""
    suffix = name.rsplit(".", 1)[-1].lower()
    structured = {"gltf": mutate_json_text, "glb": mutate_glb}.get(suffix)
    if suffix in ("toml", "obj", "mtl", "ply") and not data.startswith(b"ply\nformat binary"):
        structured = mutate_text
    if structured is not None and rng.random() < 0.7:
        try:
            out = data
            for _ in range(int(rng.integers(1, 3))):
                out = structured(out, rng)
            return out, "structure"
        except (ValueError, struct.error, UnicodeDecodeError):
            pass  # already damaged beyond parsing: damage its bytes instead
    operation = BYTE_MUTATIONS[int(rng.integers(0, len(BYTE_MUTATIONS)))]
    return operation(data, rng), operation.__name__
