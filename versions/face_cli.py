"""``python -m cassi.versions.face_cli OUT_DIR [--palate PAL.DAT] [--jaw-length MM] [--preview PNG]``

Write the generated face, with a subject's palate mapped by the one XRMB -> Parke mapping
(:func:`cassi.versions.mapping.subject_face`), as Parke's ``st1.pts``, ``st2.pts`` and
``stt.top`` into OUT_DIR (optionally with a wireframe preview).
"""
from __future__ import annotations

import argparse
import sys

from cassi.common.cliargs import positive_number
from cassi.common.errors import CassiInputError
from cassi.data.face.preview import preview_png
from cassi.common.atomic import writable_dir
from cassi.data.xrmb.files import read_pal
from cassi.versions.mapping import subject_face


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cassi.versions.face_cli",
                                 description="write the generated face in Parke's formats")
    ap.add_argument("out_dir", help="folder for st1.pts, st2.pts and stt.top")
    ap.add_argument("--palate", help="a subject's PAL.DAT (XRMB micrometres)")
    ap.add_argument("--jaw-length", type=positive_number, help="the subject's jaw length d in mm (p/d)")
    ap.add_argument("--preview", help="also write a PNG preview here")
    args = ap.parse_args(argv)
    try:
        palate = read_pal(args.palate) if args.palate else None
        face = subject_face(palate_mm=palate, jaw_length_mm=args.jaw_length)
        writable_dir(args.out_dir)  # only once the inputs are good: nothing made for a bad one
        paths = face.write(args.out_dir)
        if args.preview:
            preview_png(face, args.preview)
    except CassiInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for p in paths.values():
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
