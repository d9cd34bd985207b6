"""The coil map, ``ema.yaml``: which EMA coil plays which XRMB pellet, and the references.

Read from the speaker directory, else the corpus root. Every key is checked; a problem names the
file and the line. ``preset: <name>`` starts from a published layout (:data:`PRESETS`); keys
given beside it override the preset's. The keys::

    preset: mocha-timit         optional
    format: est                 est | pos | tsv | csv (the files' suffix: .ema .pos .tsv .csv)
    rate_hz: 500                required for a .pos file without header; else checked
    channels: 12                .pos without header: the channel count
    unit_mm: 1                  the size of the file's coordinate unit in mm
    time_column: time           tables: the time column, in time_unit (s or ms)
    task_offset: 1000           task number = task_offset + the utterance number in the file name
    coils: {ul: [ul_x, ul_y]}   a coil's channels (x, y[, z]); .pos: the channel number.
                                Default: <coil>_x, <coil>_y (and <coil>_z when the file has it)
    pellets: {UL: ul, LL: ll, T1: tt, T2: tb, T3: td, MNI: li}
    derive: {T4: {rule: extrapolate, from: [T2, T3]}, MNM: {rule: jaw-rotation}}
    references: {upper_incisor: ui, nose_bridge: bn}   also mastoid_left, mastoid_right
    head_frame: {forward: x, up: y}                     the recording's axes ("+x", "-y", "x":
                                                        the sign found from the coils), or
    head_frame: {occlusal: {front: c1, back: c2, file: bite.pos}}
    palate: PAL.DAT             or {file: palate.ema, coil: tt}

The derived-pellet rules and their figures: :mod:`cassi.data.ema.derive`.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from cassi.common.errors import CassiInputError
from cassi.data.xrmb.files import PELLETS
from cassi.data.xrmb.textlines import read_bytes

MAP_FILE = "ema.yaml"
FORMATS = {"est": ".ema", "pos": ".pos", "tsv": ".tsv", "csv": ".csv"}
REFERENCE_ROLES = ("upper_incisor", "nose_bridge", "mastoid_left", "mastoid_right")
RULES = {"extrapolate": ("from",), "midpoint": ("from",), "jaw-rotation": (), "jaw-coil": ("coil",)}
_KEYS = ("preset", "format", "rate_hz", "channels", "unit_mm", "time_column", "time_unit",
         "task_offset", "coils", "pellets", "derive", "references", "head_frame", "palate")

#: Published layouts. MOCHA-TIMIT (Wrench 1999, Queen Margaret University College; channel names
#: as in the files' EST headers, quoted in eecqin/TongueReconstruction): a Carstens AG100 in the
#: midsagittal plane at 500 Hz, coils ui (upper incisor), li (lower incisor), ul, ll, tt (tongue
#: tip), tb (blade), td (dorsum), v (velum), bn (bridge of the nose). Coordinates in units of
#: 0.01 mm. It has three tongue coils and no mandible-molar coil: T4 and MNM are derived.
#: mngu0 (Richmond, Hoole & King 2011, Interspeech, the day-1 EMA subset): a Carstens AG500 at
#: 200 Hz, released head-corrected in the midsagittal plane (channels <coil>_py forward,
#: <coil>_pz up, mm; coils T1, T2, T3, jaw, upperlip, lowerlip; its origin is taken as the upper
#: incisor). The mngu0 channel names and both unit sizes are to be checked on a real file.
PRESETS: dict[str, dict] = {
    "mocha-timit": {
        "format": "est", "rate_hz": 500, "unit_mm": 0.01,
        "pellets": {"UL": "ul", "LL": "ll", "T1": "tt", "T2": "tb", "T3": "td", "MNI": "li"},
        "derive": {"T4": {"rule": "extrapolate", "from": ["T2", "T3"]},
                   "MNM": {"rule": "jaw-rotation"}},
        "references": {"upper_incisor": "ui", "nose_bridge": "bn"},
        "head_frame": {"forward": "x", "up": "y"},
    },
    "mngu0": {
        "format": "est", "rate_hz": 200, "unit_mm": 1,
        "coils": {c: [f"{c}_py", f"{c}_pz"]
                  for c in ("T1", "T2", "T3", "jaw", "upperlip", "lowerlip")},
        "pellets": {"UL": "upperlip", "LL": "lowerlip", "T1": "T1", "T2": "T2", "T3": "T3",
                    "MNI": "jaw"},
        "derive": {"T4": {"rule": "extrapolate", "from": ["T2", "T3"]},
                   "MNM": {"rule": "jaw-rotation"}},
        "references": {"upper_incisor": "origin"},
        "head_frame": {"forward": "+x", "up": "+y"},
    },
}
#: ``references: {upper_incisor: origin}``: the file is already head-corrected, its origin the
#: upper incisor (no reference coil to fit).
ORIGIN = "origin"


@dataclass(frozen=True)
class CoilMap:
    """A resolved ``ema.yaml`` (see the module docstring); ``lines``: key path -> line."""

    path: Path
    format: str
    pellets: dict[str, str]
    derive: dict[str, dict]
    references: dict[str, str]
    head_frame: dict
    coils: dict[str, object] = field(default_factory=dict)
    rate_hz: float | None = None
    channels: int | None = None
    unit_mm: float = 1.0
    time_column: str = "time"
    time_unit: str = "s"
    task_offset: int = 1000
    palate: object = None
    preset: str | None = None
    lines: dict[str, int] = field(default_factory=dict, compare=False)

    @property
    def suffix(self) -> str:
        return FORMATS[self.format]

    def line(self, *keys: str) -> int | None:
        """The line of the deepest of ``keys`` the file itself wrote (None: the preset's)."""
        for n in range(len(keys), 0, -1):
            if ".".join(keys[:n]) in self.lines:
                return self.lines[".".join(keys[:n])]
        return None

    def error(self, reason: str, *keys: str) -> CassiInputError:
        return CassiInputError(reason + (f" (from preset {self.preset})" if self.preset and
                                         self.line(*keys) is None else ""),
                               path=self.path, line=self.line(*keys))

    def coil_names(self) -> list[str]:
        """Every coil the map uses, in a stable order."""
        used = list(self.pellets.values()) + [c for c in self.references.values() if c != ORIGIN]
        used += [r["coil"] for r in self.derive.values() if "coil" in r]
        occ = self.head_frame.get("occlusal") or {}
        if "file" not in occ:
            used += [occ[k] for k in ("front", "back") if k in occ]
        return list(dict.fromkeys(used))

    def extra_files(self) -> list[str]:
        """Files the map names besides recordings (bite plane, palate), relative names."""
        occ = self.head_frame.get("occlusal") or {}
        names = [occ["file"]] if "file" in occ else []
        pal = self.palate
        names += [pal] if isinstance(pal, str) else [pal["file"]] if isinstance(pal, dict) else []
        return names

    def resolved(self) -> dict:
        """The map as used, for the converted corpus (``ema_map.json``)."""
        keys = ("format", "rate_hz", "channels", "unit_mm", "time_column", "time_unit",
                "task_offset", "coils", "pellets", "derive", "references", "head_frame", "palate")
        out = {"source": str(self.path), "preset": self.preset}
        out.update({k: getattr(self, k) for k in keys})
        out["derived_pellets"] = sorted(self.derive, key=PELLETS.index)
        return out


def _load_yaml(text: str, path: Path) -> tuple[object, dict[str, int]]:
    """The YAML document and the line of every mapping key (``"a.b"`` -> line)."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        raise CassiInputError(f"not valid YAML: {getattr(err, 'problem', err)}", path=path,
                              line=mark.line + 1 if mark else None) from None
    lines: dict[str, int] = {}

    def walk(n, prefix: str):
        if isinstance(n, yaml.MappingNode):
            seen = set()
            for k, v in n.value:
                key = str(k.value)
                if key in seen:
                    raise CassiInputError(f"key {key!r} given twice", path=path,
                                          line=k.start_mark.line + 1)
                seen.add(key)
                lines[prefix + key] = k.start_mark.line + 1
                walk(v, prefix + key + ".")
    walk(node, "")
    data = yaml.safe_load(text) if node is not None else None
    return data, lines


def read_coil_map(path: str | os.PathLike) -> CoilMap:
    """Read and check an ``ema.yaml`` (channels are checked later, against each file)."""
    path = Path(path)
    try:
        text = read_bytes(path).decode("utf-8")
    except UnicodeDecodeError as err:
        raise CassiInputError(f"byte {err.start} is not UTF-8 text", path=path) from None
    data, lines = _load_yaml(text, path)
    if not isinstance(data, dict):
        raise CassiInputError("a coil map is a mapping of keys (e.g. 'preset: mocha-timit')",
                              path=path, line=1)
    for key in data:
        if key not in _KEYS:
            raise CassiInputError(f"unknown key {key!r} (known: {', '.join(_KEYS)})", path=path,
                                  line=lines.get(str(key)))
    raw: dict = {}
    preset = data.get("preset")
    if preset is not None:
        if preset not in PRESETS:
            raise CassiInputError(f"unknown preset {preset!r} (known: {', '.join(PRESETS)})",
                                  path=path, line=lines.get("preset"))
        raw.update(PRESETS[preset])
    raw.update({k: v for k, v in data.items() if k != "preset"})
    return _checked(raw, path=path, lines=lines, preset=preset)


def _checked(raw: dict, *, path: Path, lines: dict[str, int], preset) -> CoilMap:
    def err(reason: str, *keys: str) -> CassiInputError:
        for n in range(len(keys), 0, -1):
            if ".".join(keys[:n]) in lines:
                return CassiInputError(reason, path=path, line=lines[".".join(keys[:n])])
        return CassiInputError(reason + (f" (preset {preset})" if preset else ""), path=path)

    fmt = raw.get("format")
    if fmt not in FORMATS:
        raise err(f"format {fmt!r}: expected one of {', '.join(FORMATS)}", "format")
    pellets = _mapping(raw.get("pellets"), "pellets", err)
    derive = _mapping(raw.get("derive"), "derive", err)
    for name in list(pellets) + list(derive):
        if name not in PELLETS:
            key = "pellets" if name in pellets else "derive"
            raise err(f"{name!r} is not an XRMB pellet ({', '.join(PELLETS)})", key, name)
    both = set(pellets) & set(derive)
    if both:
        raise err(f"pellet {sorted(both)[0]} is both a coil and derived", "derive", sorted(both)[0])
    missing = [p for p in PELLETS if p not in pellets and p not in derive]
    if missing:
        raise err(f"no coil and no rule for pellet(s) {', '.join(missing)}: name a coil under "
                  f"'pellets' or a rule under 'derive'", "pellets")
    for name, rule in derive.items():
        _check_rule(name, rule, pellets, err)
    refs = _mapping(raw.get("references"), "references", err)
    if not refs:
        raise err("no reference coils: name at least the upper incisor under 'references' "
                  "(and the nose bridge or the mastoids) to follow the head", "references")
    for role in refs:
        if role not in REFERENCE_ROLES:
            raise err(f"unknown reference {role!r} (known: {', '.join(REFERENCE_ROLES)})",
                      "references", role)
    if "upper_incisor" not in refs:
        raise err("the references must name the upper incisor (the head frame's origin)",
                  "references")
    frame = _mapping(raw.get("head_frame"), "head_frame", err)
    _check_frame(frame, refs, err)
    rate, channels = raw.get("rate_hz"), raw.get("channels")
    if rate is not None and not (isinstance(rate, (int, float)) and rate > 0):
        raise err(f"rate_hz {rate!r} is not a rate in Hz", "rate_hz")
    if channels is not None and not (isinstance(channels, int) and channels > 0):
        raise err(f"channels {channels!r} is not a channel count", "channels")
    unit = raw.get("unit_mm", 1.0)
    if not (isinstance(unit, (int, float)) and unit > 0):
        raise err(f"unit_mm {unit!r} is not a length in mm", "unit_mm")
    offset = raw.get("task_offset", 1000)
    if not (isinstance(offset, int) and 0 <= offset <= 9000):
        raise err(f"task_offset {offset!r}: a whole number 0-9000", "task_offset")
    if raw.get("time_unit", "s") not in ("s", "ms"):
        raise err("time_unit: expected s or ms", "time_unit")
    coils = _mapping(raw.get("coils"), "coils", err)
    for coil, chans in coils.items():
        ok = (isinstance(chans, int) and chans > 0 if fmt == "pos" else
              isinstance(chans, list) and len(chans) in (2, 3) and
              all(isinstance(c, str) for c in chans))
        if not ok:
            want = "a channel number" if fmt == "pos" else "a list of 2 or 3 channel names"
            raise err(f"coil {coil!r}: expected {want}", "coils", coil)
    palate = raw.get("palate")
    if palate is not None and not (isinstance(palate, str) or (
            isinstance(palate, dict) and set(palate) == {"file", "coil"})):
        raise err("palate: a file name, or {file: ..., coil: ...}", "palate")
    return CoilMap(path=path, format=fmt, pellets=pellets, derive=derive, references=refs,
                   head_frame=frame, coils=coils, rate_hz=rate, channels=channels,
                   unit_mm=float(unit), time_column=str(raw.get("time_column", "time")),
                   time_unit=raw.get("time_unit", "s"), task_offset=offset, palate=palate,
                   preset=preset, lines=lines)


def _mapping(value, key: str, err) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise err(f"{key}: expected a mapping", key)
    return {str(k): v for k, v in value.items()}


def _check_rule(name: str, rule, pellets: dict, err) -> None:
    if not isinstance(rule, dict) or rule.get("rule") not in RULES:
        raise err(f"derive {name}: expected {{rule: ...}} with a rule of {', '.join(RULES)}",
                  "derive", name)
    for need in RULES[rule["rule"]]:
        if need not in rule:
            raise err(f"derive {name}: rule {rule['rule']} needs {need!r}", "derive", name)
    if "from" in rule:
        src = rule["from"]
        if not (isinstance(src, list) and len(src) == 2 and all(p in pellets for p in src)):
            raise err(f"derive {name}: 'from' must name two measured pellets (of "
                      f"{', '.join(pellets)})", "derive", name, "from")
    if rule["rule"] in ("jaw-rotation", "jaw-coil") and (name != "MNM" or "MNI" not in pellets):
        raise err(f"derive {name}: rule {rule['rule']} derives MNM from a measured MNI",
                  "derive", name)


def _check_frame(frame: dict, refs: dict, err) -> None:
    if "occlusal" in frame:
        occ = frame["occlusal"]
        if not (isinstance(occ, dict) and {"front", "back"} <= set(occ) <= {"front", "back",
                                                                          "file"}):
            raise err("head_frame.occlusal: {front: coil, back: coil} and optionally file",
                      "head_frame", "occlusal")
        if "nose_bridge" not in refs and not {"mastoid_left", "mastoid_right"} <= set(refs):
            raise err("an occlusal head frame needs the nose bridge or both mastoids among the "
                      "references (which way is up)", "references")
        return
    axes = {"x", "y", "z", "+x", "+y", "+z", "-x", "-y", "-z"}
    if set(frame) != {"forward", "up"} or not all(str(frame[k]) in axes for k in frame):
        raise err("head_frame: {forward: <axis>, up: <axis>} (x, y, z with an optional sign) "
                  "or {occlusal: {front: coil, back: coil}}", "head_frame")
    if str(frame["forward"])[-1] == str(frame["up"])[-1]:
        raise err("head_frame: forward and up are the same axis", "head_frame")
