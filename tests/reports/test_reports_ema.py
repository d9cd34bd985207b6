"""An EMA speaker's derived pellets are flagged in the report: run.json records the coil map's
rules per speaker, and the index, the subject page and the task viewer show them (real CLI run,
geometry only). The recordings are JW11's synthetic tasks: they describe the software."""
from __future__ import annotations

import json

from ema_writers import write_ema_speaker
from cassi.harness.cli import main as cli_main
from cassi.reports.report import write_report

RULES = ["T4: extrapolate from T2 and T3",
         "MNM: rigid jaw about JW11's centre of rotation, 42.6 mm behind MNI"]


def test_derived_pellets_flagged_in_the_report(tmp_path):
    corpus = tmp_path / "ema"
    write_ema_speaker(corpus, "fsew0", tasks=(5,))
    (corpus / "ema.yaml").write_text("preset: mocha-timit\n")
    run = tmp_path / "run"
    assert cli_main(["run", "--corpus", str(corpus), "--versions", "cassi-2.1",
                     "--views", "geometry", "--no-progress", "--out", str(run)]) == 0
    meta = json.loads((run / "run.json").read_text())
    assert meta["derived_pellets"] == {"fsew0": RULES}
    report = tmp_path / "report"
    write_report(run, report)
    index = (report / "index.html").read_text()
    # on the first screen: the banner comes before the report's own heading
    note = index.index("Derived pellets.")
    assert note < index.index("<h1>")
    # through Jinja's escaping (the apostrophe of JW11's)
    escaped = [r.replace("'", "&#39;") for r in RULES]
    assert f"EMA speaker fsew0: {escaped[0]}; {escaped[1]}." in index
    assert escaped[1] in (report / "subjects" / "fsew0.html").read_text()
    (viewer,) = (report / "viewer" / "fsew0").glob("*.html")
    assert escaped[0] in viewer.read_text()
