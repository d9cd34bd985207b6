"""The one aggregation: the long results table into the thesis's tables.

Reports, gates, the nightly history and the "versions compared" sentences all read these
functions; nothing else turns check rows into negatives per subject. The rules are declared,
with their reasons, next to the checks (:data:`.registry.AGGREGATION_RULES`):

1. a check counts once per subject and version: the most negatives any task file earned;
2. one fault, one charge (``Check.charged_with``);
3. Table C = Table A's lip rows judged per version + Table C's own checks;
4. Table C compared with the previous version on the same task files (:func:`table_c_rule`).
"""
from __future__ import annotations

from typing import Sequence

import pandas as pd

from cassi.harness.rubric.model import GOOD_RATINGS, RATINGS, TABLE_TOPICS, TABLES, VERSION_ORDER, rate
from cassi.harness.rubric.registry import CHECKS, MARKED_SHARE, TABLE_C_FROM_A

__all__ = ["ratings_table", "RATING_COLUMNS", "file_verdicts", "verdicts", "table_c_rule", "component_ratings", "rating_counts",
           "version_totals", "table_totals", "version_summaries", "version_comparisons", "negatives_text", "order_versions",
           "VERDICT_COLUMNS", "LEVEL_COLUMNS", "level_ratings"]

VERDICT_COLUMNS = ["version", "table", "own_table", "subject", "component", "check", "negatives",
                   "raw_negatives", "files", "fired_files", "tasks", "value", "unit", "threshold",
                   "note"]


def order_versions(versions) -> list[str]:
    """The thesis's order (:data:`VERSION_ORDER`) first, any other version after, by name."""
    known = [v for v in VERSION_ORDER if v in set(versions)]
    return known + sorted(set(versions) - set(known))


def _file(task, rep) -> str:
    return f"{int(task)}" if int(rep) == 1 else f"{int(task)}_{int(rep)}"


def file_verdicts(results: pd.DataFrame) -> pd.DataFrame:
    """Whole-task rows, one per (version, table, subject, task file, check), with Table A's lip
    rows repeated as Table C and one fault charged once per file.

    Columns: version, table, own_table (the table that declares the check: A for Table A's lip
    rows judged again in C), subject, task, rep, file, component, check, negatives (charged),
    raw_negatives (the check's own), value, unit, threshold, note.
    """
    cols = ["version", "table", "own_table", "subject", "task", "rep", "file", "component",
            "check", "negatives", "raw_negatives", "value", "unit", "threshold", "note"]
    if results is None or not len(results):
        return pd.DataFrame(columns=cols)
    df = results[(results["frame"] == -1) & results["table"].notna()].copy()
    if df.empty:
        return pd.DataFrame(columns=cols)
    for c in ("version", "subject", "table", "component", "check", "unit"):
        df[c] = df[c].astype("object").where(df[c].notna(), "")
    df["file"] = [_file(t, r) for t, r in zip(df["task"], df["rep"])]
    df["raw_negatives"] = df["negatives"].astype(int)
    df["own_table"] = df["table"]
    lip_a = df[(df["table"] == "A") & df["component"].isin(TABLE_C_FROM_A)].copy()
    lip_a["table"] = "C"
    df = pd.concat([df, lip_a], ignore_index=True)
    df["note"] = ""
    df["negatives"] = df["negatives"].astype(int)
    df = _charge_once(df, ("version", "table", "subject", "file"))  # within the file and table
    return df[cols].reset_index(drop=True)


def verdicts(results: pd.DataFrame) -> pd.DataFrame:
    """One row per (version, table, subject, component, check): the subject's verdict.

    ``negatives`` is the most any of the subject's task files earned (rule 1), after one fault,
    one charge (rule 2) applied within files and across them; ``raw_negatives`` is the check's
    own most; ``files`` / ``fired_files`` how many of the subject's files were judged / fired;
    ``tasks`` the files where it fired; ``value`` the value in the file that earned the most
    (the first file on ties); ``note`` why a fault was not charged.
    """
    fv = file_verdicts(results)
    if fv.empty:
        return pd.DataFrame(columns=VERDICT_COLUMNS)
    fv = fv.sort_values(["raw_negatives", "task", "rep"], ascending=[False, True, True],
                        kind="mergesort")
    keys = ["version", "table", "subject", "component", "check"]
    g = fv.groupby(keys, sort=True)
    out = g.first()[["own_table", "value", "unit", "threshold"]]
    out["negatives"] = g["negatives"].max()
    out["raw_negatives"] = g["raw_negatives"].max()
    out["files"] = g["file"].nunique()
    fired = fv[fv["raw_negatives"] > 0]
    out["fired_files"] = fired.groupby(keys, sort=True).size().reindex(out.index, fill_value=0)
    # the files where it fired, once each, shortest name first ("2" before "10")
    named = fired.drop_duplicates(keys + ["file"])
    named = named.assign(_len=named["file"].str.len()).sort_values(["_len", "file"],
                                                                    kind="mergesort")
    out["tasks"] = named.groupby(keys, sort=True)["file"].agg(", ".join).reindex(
        out.index, fill_value="")
    # the first note in the order above (files that earned the most first)
    noted = fv[fv["note"].astype(bool)]
    out["note"] = noted.groupby(keys, sort=True)["note"].first().reindex(out.index, fill_value="")
    out = _charge_once(out.reset_index())
    for c in ("negatives", "raw_negatives", "files", "fired_files"):
        out[c] = out[c].astype(int)
    return out[VERDICT_COLUMNS]


def table_c_rule(results: pd.DataFrame, *, fv: pd.DataFrame | None = None,
                 version_order: Sequence[str] = VERSION_ORDER) -> pd.DataFrame:
    """Table C against the previous version (rule 4), per subject and version.

    The previous version is the one before in ``version_order`` that the run judged for the
    subject. Both are compared per check on the task files they share: a check fires in more
    shared files -> "looks worse"; no check worse and a check that fired for the previous
    version now fires in at most MARKED_SHARE of those files -> "marked improvement"; both at
    once -> no change. The adjustment (+1 worse, -1 improvement, never below zero) applies only
    where the ratings before it are the same.

    Returns
    -------
    DataFrame: subject, version, previous, base (negatives before the rule), previous_base,
    adjust (-1, 0 or +1), reason, worse (checks), better (checks).
    """
    cols = ["subject", "version", "previous", "base", "previous_base", "adjust", "reason",
            "worse", "better"]
    fv = file_verdicts(results) if fv is None else fv
    c = fv[fv["table"] == "C"]
    if c.empty:
        return pd.DataFrame(columns=cols)
    base = _charge_once(fv.groupby(["version", "table", "subject", "component", "check"],
                                   sort=True)["negatives"].max().reset_index())
    base = base[base["table"] == "C"].groupby(["subject", "version"])["negatives"].sum()
    order = {v: i for i, v in enumerate(version_order)}
    rows = []
    for subject, gs in c.groupby("subject", sort=True):
        present = [v for v in version_order if v in set(gs["version"])]
        for prev, cur in zip(present, present[1:]):
            a, b = gs[gs["version"] == prev], gs[gs["version"] == cur]
            shared = set(a["file"]) & set(b["file"])
            fa, fb = (_files_fired(x[x["file"].isin(shared)]) for x in (a, b))
            checks = sorted(set(fa.index) & set(fb.index))
            worse = [f"{k} in {fb[k]} of {len(shared)} shared files against {fa[k]}"
                     for k in checks if fb[k] > fa[k]]
            better = [f"{k} in {fb[k]} of {len(shared)} shared files against {fa[k]}"
                      for k in checks if fa[k] > 0 and fb[k] <= MARKED_SHARE * fa[k]]
            nb, na = int(base.get((subject, cur), 0)), int(base.get((subject, prev), 0))
            adjust, reason = 0, ""
            if rate(nb) != rate(na):
                reason = "ratings differ: the counts tell the versions apart"
            elif worse and better:
                reason = (f"better than {prev} on some checks and worse on others: "
                          + "; ".join(better + worse))
            elif worse:
                adjust, reason = 1, f"looks worse than {prev}: " + "; ".join(worse)
            elif better:
                adjust, reason = -1, f"marked improvement over {prev}: " + "; ".join(better)
            if adjust < 0 and nb == 0:
                adjust = 0
            rows.append(dict(subject=subject, version=cur, previous=prev, base=nb,
                             previous_base=na, adjust=adjust, reason=reason,
                             worse="; ".join(worse), better="; ".join(better)))
    out = pd.DataFrame(rows, columns=cols)
    return out.sort_values(["subject", "version"], key=lambda s: s.map(order) if s.name == "version"
                           else s, kind="mergesort").reset_index(drop=True)


def _files_fired(rows: pd.DataFrame) -> pd.Series:
    """check -> in how many of ``rows``' files it earned negatives."""
    return (rows["negatives"] > 0).astype(int).groupby(rows["check"]).sum()


#: How the comparison sentences name the good ratings ("VERY GOOD/EXCELLENT").
_GOOD = "/".join(reversed(GOOD_RATINGS))


def _charge_once(out: pd.DataFrame,
                 within: Sequence[str] = ("version", "table", "subject")) -> pd.DataFrame:
    """Rule 2: a check ``charged_with`` another that fired in the same ``within`` group (by
    default the version, table and subject: across the subject's files) earns nothing (``note``
    says why when the column exists)."""
    hit = out[out["negatives"] > 0]
    groups = list(zip(*(hit[k] for k in within)))
    charged = {(*g, check) for g, check in zip(groups, hit["check"])}
    for i, g, check in zip(hit.index, groups, hit["check"]):
        c = CHECKS.get(check)
        if c is not None and c.charged_with and (*g, c.charged_with) in charged:
            out.at[i, "negatives"] = 0
            if "note" in out:
                out.at[i, "note"] = f"not charged again: {c.charged_with} charges the same fault"
    return out


def negatives_text(rows: pd.DataFrame) -> str:
    """The negatives of verdict rows (a frame, or any mapping of ``check`` and ``negatives``
    columns) as the thesis lists them: ``- text`` (``--`` for two)."""
    out = []
    for check, n in zip(rows["check"], rows["negatives"]):
        if int(n) <= 0:
            continue
        c = CHECKS.get(str(check))
        out.append(f"{'-' * int(n)} {c.text if c is not None else check}")
    return "; ".join(out)


def component_ratings(results: pd.DataFrame) -> pd.DataFrame:
    """Per version, table, subject and component: negatives, rating, negatives as text, and the
    Table C comparison (``adjust``, ``reason``).

    Returns
    -------
    DataFrame with columns version, table, thesis_table, subject, component, negatives, rating,
    text, adjust, reason.
    """
    cols = ["version", "table", "thesis_table", "subject", "component", "negatives", "rating",
            "text", "adjust", "reason"]
    v = verdicts(results)
    if v.empty:
        return pd.DataFrame(columns=cols)
    rule = table_c_rule(results).set_index(["subject", "version"])
    rows = []
    for (version, table, subject, component), g in v.groupby(
            ["version", "table", "subject", "component"], sort=True):
        n = int(g["negatives"].sum())
        text, adjust, reason = negatives_text(g), 0, ""
        if table == "C" and (subject, version) in rule.index:
            r = rule.loc[(subject, version)]
            adjust, reason = int(r["adjust"]), str(r["reason"])
            if adjust > 0:
                text = "; ".join(t for t in (text, f"- looks worse than {r['previous']}") if t)
            elif adjust < 0:
                text = "; ".join(t for t in (text, f"+ marked improvement over {r['previous']}") if t)
            n = max(0, n + adjust)
        rows.append((version, table, TABLES.get(table, ("", ""))[0], subject, component, n,
                     rate(n), text, adjust, reason))
    return pd.DataFrame(rows, columns=cols)


#: Columns of :func:`level_ratings`: ``file`` "" for a subject's rating, ``component`` "" for a
#: whole table.
LEVEL_COLUMNS = ["version", "table", "subject", "file", "component", "negatives", "rating"]


def level_ratings(results: pd.DataFrame) -> pd.DataFrame:
    """Ratings at every level a person may rate: :data:`LEVEL_COLUMNS`.

    - a subject's component: :func:`component_ratings` (``file`` "");
    - one task file's component: that file's charged negatives (:func:`file_verdicts`), a check
      counted once in the file (its most over views), summed over the component's checks;
      Table C's comparison with the previous version is per subject, so it does not apply here;
    - a whole table (``component`` ""): the sum of its components' negatives at that level.

    Every level is rated with the one scale (:func:`~.model.rate`).
    """
    cr = component_ratings(results)
    if cr.empty:
        return pd.DataFrame(columns=LEVEL_COLUMNS)
    subject = cr[["version", "table", "subject", "component", "negatives"]].assign(file="")
    fv = file_verdicts(results)
    per_file = (fv.groupby(["version", "table", "subject", "file", "component", "check"], sort=True)
                ["negatives"].max().groupby(level=[0, 1, 2, 3, 4]).sum().reset_index())
    parts = pd.concat([subject, per_file], ignore_index=True)
    whole = parts.groupby(["version", "table", "subject", "file"], sort=True)["negatives"].sum() \
        .reset_index().assign(component="")
    out = pd.concat([parts, whole], ignore_index=True)
    out["negatives"] = out["negatives"].astype(int)
    out["rating"] = [rate(n) for n in out["negatives"]]
    return out[LEVEL_COLUMNS].reset_index(drop=True)


#: Columns of a run's ratings files (``ratings.parquet`` / ``.csv``): :func:`component_ratings`'s
#: and whether the results came from a synthetic corpus.
RATING_COLUMNS = ["version", "table", "thesis_table", "subject", "component", "negatives", "rating",
                  "text", "adjust", "reason", "synthetic"]


def ratings_table(results: pd.DataFrame) -> pd.DataFrame:
    """A run's ratings files: :func:`component_ratings` (the report's tables, cell for cell) and
    ``synthetic`` (any of the subject's results from a synthetic corpus)."""
    cr = component_ratings(results)
    if cr.empty:
        return pd.DataFrame({c: pd.Series(dtype="object") for c in RATING_COLUMNS})
    synthetic = results.groupby("subject")["synthetic"].any()
    cr["synthetic"] = cr["subject"].map(synthetic).fillna(False).astype(bool)
    return cr[RATING_COLUMNS].reset_index(drop=True)


def rating_counts(results: pd.DataFrame, table: str, *, ratings: pd.DataFrame | None = None) -> pd.DataFrame:
    """Thesis Table 5.6: how many (subject, component) cells of ``table`` got each rating, per
    version (rows: versions in the thesis's order; columns: :data:`RATINGS`)."""
    cr = component_ratings(results) if ratings is None else ratings
    cr = cr[cr["table"] == table]
    counts = pd.crosstab(cr["version"], cr["rating"]) if not cr.empty else pd.DataFrame()
    counts = counts.reindex(columns=list(RATINGS), fill_value=0)
    return counts.reindex(order_versions(cr["version"].unique()), fill_value=0).astype(int)


def table_totals(results: pd.DataFrame, *, ratings: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per version and table: negatives summed over the table's cells (columns version, table,
    negatives; versions in the thesis's order)."""
    cr = component_ratings(results) if ratings is None else ratings
    if cr.empty:
        return pd.DataFrame(columns=["version", "table", "negatives"])
    t = cr.groupby(["version", "table"])["negatives"].sum().astype(int).reset_index()
    rank = {v: i for i, v in enumerate(order_versions(t["version"].unique()))}
    return t.sort_values(["version", "table"], key=lambda c: c.map(rank) if c.name == "version"
                         else c, kind="mergesort").reset_index(drop=True)


def version_totals(results: pd.DataFrame, *, ratings: pd.DataFrame | None = None) -> pd.DataFrame:
    """Per version: total negatives over every table cell (the nightly history's number), the
    sum of :func:`table_totals`."""
    t = table_totals(results, ratings=ratings)
    if t.empty:
        return pd.DataFrame(columns=["version", "negatives"])
    t = t.groupby("version", sort=False)["negatives"].sum()
    return t.rename("negatives").reset_index()


def _per_check(v: pd.DataFrame, table: str, prev: str, cur: str) -> pd.DataFrame:
    """Negatives per check of two versions in a table, summed over subjects: columns a, b."""
    t = v[v["table"] == table]
    a = t[t["version"] == prev].groupby("check")["negatives"].sum()
    b = t[t["version"] == cur].groupby("check")["negatives"].sum()
    return pd.concat([a.rename("a"), b.rename("b")], axis=1).fillna(0).astype(int)


def _deciding(both: pd.DataFrame, *, limit: int = 4) -> str:
    """The checks that tell two versions apart in a table (``both``: :func:`_per_check`), or,
    when none does, the checks that fired for both."""
    diff = both[both["a"] != both["b"]].copy()
    if len(diff):
        diff["d"] = (diff["b"] - diff["a"]).abs()
        diff = diff.sort_values(["d"], ascending=False, kind="mergesort").head(limit)
        return "decided by " + ", ".join(f"{k} ({r.b} against {r.a} negatives)"
                                          for k, r in diff.iterrows())
    same = both[both["a"] > 0]
    if not len(same):
        return "no check fired for either"
    return "the same faults decided both: " + ", ".join(
        f"{k} ({_n(r.a)} each)" for k, r in same.head(limit).iterrows())


def _rule_note(adjust: pd.Series, prev: str, cur: str) -> str:
    """Why two versions whose checks all agree have different totals: what Table C's comparison
    rule added to each (summed over subjects)."""
    parts = [f"{name} {int(adjust.get(name, 0)):+d} against the version before it"
             for name in (prev, cur) if int(adjust.get(name, 0))]
    return f" (every check agrees; Table C's comparison rule: {', '.join(parts)})"


def _list(names: list[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _n(n: int) -> str:
    return f"{int(n)} negative" + ("" if int(n) == 1 else "s")


def version_summaries(results: pd.DataFrame) -> list[str]:
    """Sentences comparing each version with the one before it, per table, and naming the checks
    that decided; Table F also names its worst version.

    "cassi-2.1 improves lip placement over cassi-2.0: 10 VERY GOOD/EXCELLENT cells against 6,
    31 negatives against 40; decided by lips_never_touch (3 against 9 negatives), ..."
    """
    return [s for _, s in version_comparisons(results)]


def version_comparisons(results: pd.DataFrame) -> list[tuple[str, str]]:
    """:func:`version_summaries` as (table, sentence) pairs, for reports that group them."""
    cr = component_ratings(results)
    if cr.empty:
        return []
    v = verdicts(results)
    # Table C's rule, as component_ratings applied it: once per subject and version
    rule = cr[cr["table"] == "C"].drop_duplicates(["subject", "version"])
    adjust = rule.groupby("version")["adjust"].sum()
    out = []
    for table in sorted(cr["table"].unique()):
        sub = cr[cr["table"] == table]
        counts = rating_counts(results, table, ratings=cr)
        good = counts[list(GOOD_RATINGS)].sum(axis=1)
        neg = sub.groupby("version")["negatives"].sum()
        names = list(counts.index)
        topic = TABLE_TOPICS.get(str(table), f"table {table}")
        for prev, cur in zip(names, names[1:]):
            ga, gb, na, nb = int(good[prev]), int(good[cur]), int(neg[prev]), int(neg[cur])
            both = _per_check(v, table, prev, cur)
            note = ""
            if (gb != ga or nb != na) and (both["a"] == both["b"]).all():
                # Every check agrees: the totals differ only by Table C's rule, which charges
                # each version against the one before it, not against this pair.
                verb = "matches"
                note = _rule_note(adjust, prev, cur)
            elif gb != ga:
                verb = "improves" if gb > ga else "worsens"
            elif nb != na:
                verb = ("improves (same ratings, fewer negatives)" if nb < na
                        else "worsens (same ratings, more negatives)")
            else:
                verb = "matches"
            out.append((table, f"{cur} {verb} {topic} over {prev}: {gb} {_GOOD} cells "
                               f"against {ga}, {_n(nb)} against {na}{note}; "
                               f"{_deciding(both)}"))
        if table == "F" and len(names) > 1:
            n = neg.reindex(names).astype(int)
            worst = [k for k in names if n[k] == n.max()]
            best = [k for k in names if n[k] == n.min()]
            out.append((table, f"Fidelity to the recording (cassi-farm's Table F): worst "
                               f"{_list(worst)} with {_n(n.max())}"
                               + ("" if len(worst) == len(names)
                                  else f"; best {_list(best)} with {_n(n.min())}")))
    return out
