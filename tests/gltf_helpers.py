"""Reading a binary glTF (.glb) back in tests: its JSON and binary chunks, and an accessor's
values (sparse substitution applied)."""
from __future__ import annotations

import json
import struct

import numpy as np

DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32,
          5126: np.float32}
WIDTH = {"SCALAR": 1, "VEC3": 3}


def chunks(data: bytes) -> tuple[dict, bytes]:
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and length == len(data)
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A and jlen % 4 == 0
    gltf = json.loads(data[20:20 + jlen])
    blen, btype = struct.unpack_from("<II", data, 20 + jlen)
    assert btype == 0x004E4942 and blen % 4 == 0
    assert 20 + jlen + 8 + blen == len(data)
    binary = data[28 + jlen:28 + jlen + blen]
    assert gltf["buffers"] == [{"byteLength": len(binary)}] or \
        0 <= len(binary) - gltf["buffers"][0]["byteLength"] < 4
    return gltf, binary


def accessor(gltf: dict, binary: bytes, index: int) -> np.ndarray:
    """Accessor ``index`` as (count, width) in its stored type (sparse substitution applied)."""
    acc = gltf["accessors"][index]
    dt, width, n = np.dtype(DTYPES[acc["componentType"]]), WIDTH[acc["type"]], acc["count"]
    out = np.zeros((n, width), dt)
    if "bufferView" in acc:
        view = gltf["bufferViews"][acc["bufferView"]]
        stride = view.get("byteStride", dt.itemsize * width)
        start = view["byteOffset"] + acc.get("byteOffset", 0)
        for c in range(width):
            out[:, c] = np.ndarray((n,), dt, binary, start + c * dt.itemsize, (stride,))
    if "sparse" in acc:
        sp = acc["sparse"]
        iv, vv = (gltf["bufferViews"][sp[k]["bufferView"]] for k in ("indices", "values"))
        idx = np.frombuffer(binary, DTYPES[sp["indices"]["componentType"]], sp["count"],
                            iv["byteOffset"] + sp["indices"].get("byteOffset", 0))
        assert np.all(np.diff(idx.astype(np.int64)) > 0)  # glTF: strictly increasing
        out[idx] = np.frombuffer(binary, dt, sp["count"] * width,
                                 vv["byteOffset"] + sp["values"].get("byteOffset", 0)
                                 ).reshape(-1, width)
    return out
