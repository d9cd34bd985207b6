"""The report's task viewer: one page per evaluated task file, every version's face in 3D.

Each page (``viewer/<subject>/<task>_<rep>.html``) loads three classic scripts, since Chromium
blocks module imports and fetch() on file:// pages: the vendored three.js subset
(``static/three.min.js``, MIT, see ``static/README.md``), ``static/viewer.js`` and the task
file's data (``<task>_<rep>.js``: ``window.CASSI_VIEWER = {...}``, JSON). The data is what the
geometry stage kept (:mod:`cassi.harness.evaluation.viewerdata`): typed arrays travel as base64,
the frame-to-frame vertex changes deflated (the page inflates them with the browser's own
DecompressionStream). Strings from data files reach the page only inside that JSON and are
set as text by the script, never as HTML.

The address's fragment selects what opens: ``#frame=ROW&a=VERSION&b=VERSION&check=NAME&view=VIEW``
(:func:`viewer_href`; the page adds ``mode=overlay|diff`` and ``pellets=0`` as they change); a
subject page's negatives link there, at the frame that earned them and in the view the check is
judged from (its registry ``view``).
"""
from __future__ import annotations

import base64
import hashlib
import json
import os
import urllib.parse
import wave
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pandas as pd

from cassi.common.atomic import atomic_write_bytes, atomic_write_text, link_or_copy
from cassi.data.corpus.disk import Corpus
from cassi.data.xrmb.files import NOMINAL_PERIOD_US, PELLETS
from cassi.harness.evaluation.frames import linked_view, viewer_stride
from cassi.harness.evaluation.stages import read_masks_blob
from cassi.harness.evaluation.viewerdata import read_viewer_blob
from cassi.harness.rubric import CHECKS
from cassi.harness.rubric.model import TABLE_TOPICS, TABLES
from cassi.harness.rubric.image import FrameMasks, mouth_opening
from cassi.harness.rubric.tables import file_verdicts
from cassi.renderer.gltf import AXES
from cassi.renderer.views import VIEWS, material_for
from cassi.reports.memo import code_digest, content_ids
from cassi.reports.runio import Run, order_versions

__all__ = ["VIEWER_DIR", "STATIC_DIR", "viewer_page", "viewer_href", "write_viewers",
           "version_payload", "viewer_payload", "write_viewer_page", "copy_static",
           "TABLE_COLOURS", "MASK_COLOURS", "mask_overlay", "stored_overlay", "table_legend"]

VIEWER_DIR = "viewer"
STATIC_DIR = "static"
_STATIC_FILES = ("three.min.js", "three.LICENSE.txt", "viewer.js")
#: One colour per rubric table for the timeline's event marks (colour-blind safe: Okabe-Ito).
TABLE_COLOURS = {"A": "#E69F00", "B": "#56B4E9", "C": "#009E73", "D": "#F0E442",
                 "E": "#0072B2", "F": "#D55E00", "G": "#CC79A7"}


def table_legend() -> list[dict]:
    """The timeline's legend: each rubric table's letter, mark colour, thesis table and topic."""
    return [{"letter": t, "colour": TABLE_COLOURS[t], "thesis": TABLES[t][0],
             "title": TABLES[t][1], "topic": TABLE_TOPICS[t]} for t in TABLES]


def viewer_page(subject_slug: str, task: int, rep: int) -> str:
    """The viewer page of a task file, relative to the report."""
    return f"{VIEWER_DIR}/{subject_slug}/{int(task):03d}_{int(rep)}.html"


def viewer_href(subject_slug: str, task: int, rep: int, *, frame: int | None = None,
                a: str | None = None, b: str | None = None, check: str | None = None,
                view: str | None = None, base: str = "") -> str:
    """A link to the viewer page, opening at ``frame`` with versions ``a`` (and ``b``),
    ``check``'s event highlighted, in ``view`` (default: the view ``check`` is judged from);
    ``base``: the linking page's way to the report's root."""
    if view is None and check is not None:
        view = linked_view(check)
    params = {k: v for k, v in (("frame", frame), ("a", a), ("b", b), ("check", check),
                                ("view", view)) if v is not None}
    frag = urllib.parse.urlencode(params, quote_via=urllib.parse.quote)
    return base + viewer_page(subject_slug, task, rep) + (f"#{frag}" if frag else "")


_JS_TYPES = {np.dtype(np.float32): "float32", np.dtype(np.int16): "int16",
             np.dtype(np.int32): "int32", np.dtype(np.uint16): "uint16",
             np.dtype(np.int8): "int8", np.dtype(np.uint8): "uint8"}


def _array(a: np.ndarray, *, stream: bytes | None = None) -> dict:
    """A typed array for the page: its little-endian bytes as base64, or ``stream``, the zlib
    stream of those bytes the geometry stage stored (passed through, not compressed again)."""
    a = np.ascontiguousarray(a)
    dtype = _JS_TYPES[a.dtype.newbyteorder("=")]
    raw = stream if stream is not None else a.astype(a.dtype.newbyteorder("<")).tobytes()
    return {"dtype": dtype, "shape": list(a.shape), "deflate": stream is not None,
            "b64": base64.b64encode(raw).decode("ascii")}


def _three(p) -> list[float]:
    """A Parke point or direction on the viewer's axes (three.js = glTF: Y up, +Z to the face's
    front, :data:`cassi.renderer.gltf.AXES`)."""
    return [float(p[i]) for i in AXES]


def _views() -> dict:
    """The renderer's four cameras on the viewer's axes (one home for the cameras)."""
    out = {}
    for name, v in VIEWS.items():
        c = v.camera
        out[name] = {"origin": _three(c.origin), "target": _three(c.target), "up": _three(c.up),
                     "fov": float(c.fov), "half": bool(v.half),
                     "clip_above_palate": v.clip_above_palate, "description": v.description}
    return out


def version_payload(data, events: list[dict], renders: list[dict]) -> dict:
    """One version of the task file: its geometry, pellet sites, events and renders."""
    colours = []
    for part in data.parts:
        m = material_for(part)
        colours.append({"part": part, "rgb": [float(x) for x in m.rgb],
                        "roughness": float(min(1.0, max(m.alpha, 0.05) ** 0.5))})
    palate = [i for i, p in enumerate(data.parts) if p.startswith("palate")]
    top = None
    if palate:
        rows = np.unique(data.gather[np.unique(data.triangles[np.isin(data.part_of, palate)])])
        top = float(data.base[rows, 2].max())
    return {
        "frames": _array(data.frames.astype(np.int32)),
        "time_ms": _array((data.time_us / 1000.0).astype(np.float32)),
        "base": _array(data.base.astype(np.float32)),
        "moving": _array(data.moving.astype(np.int32)), "step": data.step,
        "q0": _array(data.q0.astype(np.int16)),
        "dq": _array(data.dq, stream=data.deflated["dq"]),
        "gather": _array(data.gather.astype(np.int32)), "sign": _array(data.sign.astype(np.int8)),
        "triangles": _array(data.triangles, stream=data.deflated["triangles"]),
        "part_of": _array(data.part_of.astype(np.int16)), "parts": colours,
        "palate_top": top, "model": _array(data.model, stream=data.deflated["model"]),
        # the pellets' map into this face (Parke (x, z) = XRMB (x, y) mm * units_per_mm +
        # xrmb_origin; None for older data): 3D pellet markers, and the A/B distance in mm
        "units_per_mm": data.units_per_mm,
        "xrmb_origin": None if data.xrmb_origin is None else [float(x) for x in data.xrmb_origin],
        "events": events, "renders": renders}


def _events(results: pd.DataFrame) -> dict[tuple, list[dict]]:
    """(subject, task, rep, version) -> every check of the rubric that holds a frame there: its
    table, negatives as the report charges them for the file (:func:`file_verdicts`: one fault,
    one charge), the check's own negatives and the note when another check charges the fault,
    and every frame the results point at for it."""
    r = results[results["table"].notna() & (results["view"] != "trace")]
    keys = ["subject", "task", "rep", "version", "check"]
    fv = file_verdicts(results)
    fv = fv[fv["table"] == fv["own_table"]].sort_values("raw_negatives")  # the most wins
    # The check's whole-file row is the one source of what a page says of it (the subject
    # pages and tables read the same rows); an evidence row's value is a frame's, in the
    # measure's own terms, and is never shown under the check's name.
    whole = {(s, int(t), int(p), v, c): (int(n), int(raw), str(note), value, unit)
             for s, t, p, v, c, n, raw, note, value, unit
             in fv[[*keys, "negatives", "raw_negatives", "note", "value", "unit"]]
             .itertuples(index=False, name=None)}
    found: dict[tuple, dict[str, dict]] = {}
    ev = r[r["frame"] >= 0]
    for row in ev[[*keys, "table", "component", "frame", "negatives"]] \
            .itertuples(index=False, name=None):
        subject, task, rep, version, check, table, component, frame, neg = row
        file = (subject, int(task), int(rep), version)
        e = found.setdefault(file, {}).get(check)
        if e is None:
            c = CHECKS.get(check)
            charged, raw, note, value, unit = whole.get((*file, check),
                                                        (int(neg), int(neg), "", None, ""))
            e = found[file][check] = {
                "negatives": charged, "raw_negatives": raw, "note": note,
                "check": str(check), "table": str(table),
                "component": "" if pd.isna(component) else str(component),
                "text": c.text if c else str(check),
                "frames": set(),
                "value": None if value is None or pd.isna(value) else float(value),
                "unit": "" if unit is None or pd.isna(unit) else str(unit)}
        e["frames"].add(int(frame))
    out = {}
    for file, checks in found.items():
        events = [{**e, "frames": sorted(e["frames"])} for e in checks.values()]
        events.sort(key=lambda e: (-e["negatives"], -e["raw_negatives"], e["table"], e["frames"][0],
                                   e["check"]))
        out[file] = events
    return out


#: The overlay's colours (RGBA) for what the image checks see in a frame's masks.
MASK_COLOURS = (("lips", (230, 40, 40, 150)), ("upper_teeth", (250, 210, 0, 170)),
                ("lower_teeth", (0, 200, 230, 170)), ("tongue", (200, 0, 200, 150)),
                ("opening", (30, 60, 200, 110)))


def mask_overlay(blob: bytes, frame: int, dest: Path) -> Path:
    """An RGBA PNG of what the image checks read in a frame (``masks-<frame>`` blob): lips,
    upper and lower teeth (split as the checks split them), tongue and the mouth opening,
    coloured as :data:`MASK_COLOURS`, transparent elsewhere; shown over the render."""
    fm = FrameMasks.of(frame, read_masks_blob(blob).full())
    layers = {"lips": fm.lips, "upper_teeth": fm.upper_teeth, "lower_teeth": fm.lower_teeth,
              "tongue": fm.tongue, "opening": mouth_opening(fm.lips) & ~fm.teeth & ~fm.tongue}
    rgba = np.zeros((*fm.lips.shape, 4), np.uint8)
    for name, colour in MASK_COLOURS:
        rgba[layers[name]] = colour
    atomic_write_bytes(dest, iio.imwrite("<bytes>", rgba, extension=".png"))
    return dest


def stored_overlay(blob_path, frame: int, dest: Path, cache: Path | None = None) -> Path:
    """:func:`mask_overlay` of the masks blob at ``blob_path``; with ``cache`` (a nightly
    store's media) an overlay drawn before from the same blob, frame and code is linked."""
    if cache is None:
        return mask_overlay(Path(blob_path).read_bytes(), frame, dest)
    doc = ["mask-overlay", content_ids([blob_path])[0], int(frame), code_digest()]
    cached = Path(cache) / f"{hashlib.sha256(json.dumps(doc).encode()).hexdigest()}.png"
    if cached.is_file():
        return link_or_copy(cached, dest)
    mask_overlay(Path(blob_path).read_bytes(), frame, dest)
    cached.parent.mkdir(parents=True, exist_ok=True)
    link_or_copy(dest, cached)
    return dest


def copy_static(out: Path) -> None:
    here = Path(__file__).parent / STATIC_DIR
    (out / STATIC_DIR).mkdir(parents=True, exist_ok=True)
    for name in _STATIC_FILES:
        dest = out / STATIC_DIR / name
        src = here / name
        data = src.read_bytes()
        if not dest.is_file() or dest.read_bytes() != data:
            atomic_write_bytes(dest, data)


def write_viewers(run: Run, out: Path, env, *, slug, audio_for=None, images=None, memo=None,
                  key_of=None) -> dict:
    """Write every task file's viewer page and data; returns ``(subject, task, rep) -> page``
    (relative to ``out``) for the task files whose geometry jobs kept viewer data.

    ``images(subject, task, rep, version) -> [{"frame", "view", "href"[, "mask"]}]``: the
    renders to show beside the 3D view (hrefs relative to the page), with an optional
    ``images.prefetch([(subject, task, rep, version), ...])`` that prepares those of the pages
    to be made and an optional ``images.note`` (what the renders shown leave out, said on each
    page); ``audio_for(subject, task, rep)``: the task's WAV (copied beside the page) or
    None. ``memo`` (:class:`~cassi.reports.memo.Memo`) with ``key_of(subject, task, rep)`` (its
    key document, None: none): a page made before of the same inputs is linked, not made
    again.
    """
    att = run.attachments
    att = att[att["name"] == "viewer"] if len(att) else att
    if not len(att):
        return {}
    copy_static(out)
    pages, todo = {}, []
    for (subject, task, rep), g in att.groupby(["subject", "task", "rep"], sort=True):
        task, rep = int(task), int(rep)
        page = viewer_page(slug(subject), task, rep)
        pages[(subject, task, rep)] = page
        doc = key_of(subject, task, rep) if memo is not None and key_of is not None else None
        key = memo.key("viewer", doc) if doc is not None else None
        if memo is None or not memo.reuse(key)[0]:
            todo.append((subject, task, rep, g, key))
    if not todo:
        return pages
    if images is not None and hasattr(images, "prefetch"):
        images.prefetch([(s, t, r, v) for s, t, r, g, _ in todo for v in g["version"].unique()])
    events = _events(run.results)
    for subject, task, rep, g, key in todo:
        files = _write_viewer(run, out, env, subject, task, rep, g, pages[(subject, task, rep)],
                              events=events, slug=slug, audio_for=audio_for, images=images)
        if memo is not None:
            memo.keep(key, files, None)
    return pages


def _write_viewer(run: Run, out: Path, env, subject: str, task: int, rep: int,
                  att: pd.DataFrame, page: str, *, events, slug, audio_for, images) -> list[Path]:
    """One task file's viewer page (:func:`write_viewers`); returns every file it shows that
    lies in the report (page, data, sound, renders, mask overlays)."""
    versions, first, shown = {}, None, []
    for version in order_versions(att["version"].unique()):
        path = Path(att[att["version"] == version]["path"].iloc[0])
        data = read_viewer_blob(path.read_bytes())
        first = first or data  # the measured pellets are the same in every version
        rend = images(subject, task, rep, version) if images else []
        shown += rend
        versions[version] = version_payload(
            data, events.get((subject, task, rep, version), []), rend)
    dest = out / page
    stem = dest.stem
    audio = audio_for(subject, task, rep) if audio_for else None
    audio_href = None
    files = [dest, dest.with_suffix(".js")]
    if audio is not None and Path(audio).is_file():
        link_or_copy(audio, dest.parent / f"{stem}.wav")
        audio_href = f"{stem}.wav"
        files.append(dest.parent / audio_href)
    payload = viewer_payload(run, subject, task, rep, versions, first, audio=audio,
                             audio_href=audio_href,
                             subject_page=f"../../subjects/{slug(subject)}.html")
    write_viewer_page(dest, payload, env, static="../../static", index="../../index.html",
                      renders_note=getattr(images, "note", None))
    files += [Path(os.path.normpath(dest.parent / item[k])) for item in shown
              for k in ("href", "mask") if k in item]
    return files


def viewer_payload(run: Run, subject: str, task: int, rep: int, versions: dict, first, *,
                   audio=None, audio_href: str | None = None,
                   subject_page: str | None = None) -> dict:
    """What a viewer page's script reads (``window.CASSI_VIEWER``): ``versions`` maps each name
    the page shows to its :func:`version_payload`; ``first`` is one version's viewer data (the
    measured pellets are the same in every version); ``audio``: the sound beside the page
    (``audio_href``), whose waveform the timeline draws."""
    return {
        "subject": str(subject), "task": task, "rep": rep, "synthetic": run.synthetic,
        "derived": run.derived.get(str(subject), []),
        "versions": list(versions), "version_data": versions,
        "measured": _array(first.measured, stream=first.deflated["measured"]),
        "measured_frames": _array(first.frames.astype(np.int32)),
        "pellets": list(PELLETS), "views": _views(),
        "stride": viewer_stride(1e6 / _rate(first)),
        "rate_hz": _rate(first), "audio": audio_href, "labels": _labels(run, subject, task, rep),
        "waveform": _waveform(audio) if audio_href else None,
        "table_colours": TABLE_COLOURS, "subject_page": subject_page}


def write_viewer_page(dest: Path, payload: dict, env, *, static: str, index: str | None,
                      blind: bool = False, renders_note: str | None = None) -> None:
    """A viewer page (``dest``) and its data (``dest`` with ``.js``); ``static``: the way from
    the page to the viewer's scripts; ``index`` None: no way back to a report; ``blind``: a
    rating session's page, without the rubric's events or links to what fired."""
    atomic_write_text(dest.with_suffix(".js"), "window.CASSI_VIEWER = "
                      + json.dumps(payload, separators=(",", ":"), allow_nan=False) + ";\n")
    atomic_write_text(dest, env.get_template("viewer.html.j2").render(
        subject=payload["subject"], task=payload["task"], rep=payload["rep"],
        synthetic=payload["synthetic"], versions=payload["versions"], data=f"{dest.stem}.js",
        derived={payload["subject"]: payload["derived"]} if payload.get("derived") else {},
        static=static, index=index, subject_page=payload["subject_page"], blind=blind,
        legend=table_legend(), stride=payload["stride"], renders_note=renders_note))


def _rate(data) -> float:
    """The recording's rows per second, from the kept rows' numbers and times (XRMB's when
    fewer than two rows were kept)."""
    t = np.asarray(data.time_us, np.float64)
    f = np.asarray(data.frames, np.float64)
    if len(t) < 2 or f[-1] == f[0]:
        return 1e6 / NOMINAL_PERIOD_US
    return float((f[-1] - f[0]) / ((t[-1] - t[0]) / 1e6))


def _labels(run: Run, subject: str, task: int, rep: int) -> dict | None:
    """The task's phone and word intervals (seconds) when the run's corpus has an alignment."""
    root = run.meta.get("corpus_resolved")
    try:
        al = Corpus(root).subject(subject).alignment(task, rep) if root else None
    except Exception:  # noqa: BLE001 - a moved corpus must not stop the report
        al = None
    if al is None:
        return None

    def tier(df):
        if df is None or not len(df):
            return []
        return [[float(a), float(b), str(t)] for a, b, t in
                zip(df["start_s"], df["end_s"], df["label"])]
    return {"words": tier(al.words), "phones": tier(al.phones)}


def _waveform(path, bins: int = 2000) -> dict | None:
    """Min and max of the task's sound (PCM WAV) in ``bins`` bins: the timeline's waveform."""
    try:
        with wave.open(str(path), "rb") as w:
            rate, width, channels = w.getframerate(), w.getsampwidth(), w.getnchannels()
            raw = w.readframes(w.getnframes())
    except (OSError, EOFError, wave.Error):
        return None
    if width not in (1, 2, 4):
        return None
    x = np.frombuffer(raw, {1: np.uint8, 2: "<i2", 4: "<i4"}[width]).astype(np.float64)
    if width == 1:
        x = x - 128.0
    x = x.reshape(-1, channels).mean(axis=1) / float(2 ** (8 * width - 1))
    if not len(x):
        return None
    n = max(1, len(x) // bins)
    seconds = len(x) / rate
    x = x[: (len(x) // n) * n].reshape(-1, n)
    return {"seconds": float(seconds), "min": np.round(x.min(axis=1), 4).tolist(),
            "max": np.round(x.max(axis=1), 4).tolist()}
