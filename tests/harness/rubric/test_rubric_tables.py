"""The one aggregation (cassi.harness.rubric.tables): planted results tables prove every rule
of rubric.md and thesis 5.3 -- a fault counts once per subject, one fault one charge, Table C
from Table A's lips, and Table C's comparison with the previous version (worse, marked
improvement, both, ratings already different)."""
from __future__ import annotations

import pandas as pd

from cassi.harness import rubric as R


def rows(version, items, *, subject="JW11", task=5, rep=1):
    """Whole-task rows: items = [(check, negatives)] for one task file."""
    return pd.DataFrame([dict(subject=subject, task=task, rep=rep, version=version, view="geometry",
                              frame=-1, check=k, table=R.CHECKS[k].table,
                              component=R.CHECKS[k].component, value=1.0, unit="mm",
                              threshold=0.0, negatives=n, detail="") for k, n in items])


def cell(results, table, version, component="lips", subject="JW11"):
    cr = R.component_ratings(results).set_index(["table", "version", "subject", "component"])
    return cr.loc[(table, version, subject, component)]


def test_a_fault_counts_once_per_subject_with_its_worst_file():
    res = pd.concat([rows("cassi-1.0", [("lips_apart_at_start", 1), ("tongue_through_teeth", 1)]),
                     rows("cassi-1.0", [("lips_apart_at_start", 2)], task=21)])
    # per-frame evidence rows never count
    ev = rows("cassi-1.0", [("tongue_through_teeth", 3)]).assign(frame=10)
    res = pd.concat([res, ev])
    assert cell(res, "A", "cassi-1.0")["negatives"] == 2
    assert cell(res, "A", "cassi-1.0", "tongue")["negatives"] == 1
    v = R.verdicts(res).set_index(["table", "check"])
    assert v.loc[("A", "lips_apart_at_start"), "tasks"] == "5, 21"
    assert v.loc[("A", "lips_apart_at_start"), "fired_files"] == 2
    assert cell(res, "A", "cassi-1.0")["text"] == "-- lips too far apart at the start or end, not touching"


def test_table_c_is_table_a_lips_plus_its_own_checks():
    res = rows("cassi-1.0", [("lips_apart_at_start", 1), ("tongue_through_teeth", 1),
                             ("lips_too_large_moving", 1)])
    c = cell(res, "C", "cassi-1.0")
    assert c["negatives"] == 2                        # the lip row of A + C's own, not the tongue
    assert "tongue" not in c["text"] and "too far apart" in c["text"]
    assert cell(res, "A", "cassi-1.0")["negatives"] == 1
    # Table G's whole-file lips_never_touch (cassi-farm's measure) is not a Table A row: not in C
    g = rows("cassi-1.0", [("lips_never_touch", 2)])
    assert set(R.verdicts(g)["table"]) == {"G"}


def test_one_fault_one_charge():
    # lips held apart at the first and last frame are lips that do not close where the speaker
    # closes them: one fault, charged once in C
    both = rows("cassi-1.0", [("lips_apart_at_start", 1), ("lips_do_not_close", 1)])
    c = cell(both, "C", "cassi-1.0")
    assert c["negatives"] == 1 and "do not close where" not in c["text"]
    v = R.verdicts(both).set_index(["table", "check"])
    assert v.loc[("C", "lips_do_not_close"), "raw_negatives"] == 1
    assert "lips_apart_at_start" in v.loc[("C", "lips_do_not_close"), "note"]
    # ... also when another of the subject's files showed the lips apart
    across = pd.concat([rows("cassi-1.0", [("lips_apart_at_start", 0), ("lips_do_not_close", 1)]),
                        rows("cassi-1.0", [("lips_apart_at_start", 2)], task=21)])
    assert cell(across, "C", "cassi-1.0")["negatives"] == 2
    # lips that touch at both frames but stay open in the speaker's closures: charged
    alone = rows("cassi-1.0", [("lips_apart_at_start", 0), ("lips_do_not_close", 1)])
    assert cell(alone, "C", "cassi-1.0")["negatives"] == 1
    # Table G: lips that never touch in the file are closures seen open, charged once there
    g = rows("cassi-1.0", [("shape_lip_contact", 2), ("lips_never_touch", 1)])
    assert cell(g, "G", "cassi-1.0")["negatives"] == 2


def _two_files(version, first, second):
    return pd.concat([rows(version, first, task=5), rows(version, second, task=21)])


def test_table_c_looks_worse_on_the_same_files_earns_one_more():
    # same rating (1 negative each) but 2.1 shows its fault in both shared files, 2.0 in one
    prev = _two_files("cassi-2.0", [("lips_overlap", 1)], [("lips_overlap", 0)])
    cur = _two_files("cassi-2.1", [("lips_overlap", 1)], [("lips_overlap", 1)])
    res = pd.concat([prev, cur])
    c = cell(res, "C", "cassi-2.1")
    assert c["negatives"] == 2 and c["adjust"] == 1
    assert "looks worse than cassi-2.0" in c["text"] and "lips_overlap in 2 of 2" in c["reason"]
    assert cell(res, "C", "cassi-2.0")["negatives"] == 1      # the first version has no previous
    # Table A is judged per version alone: no comparison there
    assert cell(res, "A", "cassi-2.1")["negatives"] == 1


def test_table_c_marked_improvement_earns_one_fewer():
    # same rating (1 negative) but the fault is gone from half the shared files and nothing worse
    prev = _two_files("cassi-1.0", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 1)])
    cur = _two_files("cassi-2.0", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 0)])
    c = cell(pd.concat([prev, cur]), "C", "cassi-2.0")
    assert c["negatives"] == 0 and c["adjust"] == -1
    assert "marked improvement over cassi-1.0" in c["reason"]


def test_table_c_better_and_worse_at_once_keeps_the_count():
    prev = _two_files("cassi-1.0", [("lips_apart_at_start", 1), ("lips_overlap", 0)],
                      [("lips_apart_at_start", 1), ("lips_overlap", 0)])
    cur = _two_files("cassi-2.0", [("lips_apart_at_start", 0), ("lips_overlap", 1)],
                     [("lips_apart_at_start", 0), ("lips_overlap", 0)])
    c = cell(pd.concat([prev, cur]), "C", "cassi-2.0")
    assert c["adjust"] == 0 and c["negatives"] == 1


def test_table_c_rule_applies_only_where_the_ratings_are_the_same():
    prev = _two_files("cassi-1.0", [("lips_apart_at_start", 2)], [("lips_apart_at_start", 0)])
    cur = _two_files("cassi-2.0", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 1)])
    c = cell(pd.concat([prev, cur]), "C", "cassi-2.0")
    assert c["adjust"] == 0 and c["negatives"] == 1 and "ratings differ" in c["reason"]


def test_table_c_compares_only_the_files_both_versions_judged():
    prev = rows("cassi-1.0", [("lips_overlap", 1)], task=5)
    cur = _two_files("cassi-2.0", [("lips_overlap", 1)], [("lips_overlap", 1)])
    c = cell(pd.concat([prev, cur]), "C", "cassi-2.0")
    assert c["adjust"] == 0      # task 21 was not judged for 1.0: 1 of 1 shared files each


def test_summaries_name_the_checks_that_decided():
    same = pd.concat([rows("cassi-1.0", [("lips_apart_at_start", 1)]),
                      rows("cassi-2.0", [("lips_apart_at_start", 1)])])
    s = [x for x in R.version_summaries(same) if "lip placement" in x][0]
    assert "matches" in s and "the same faults decided both: lips_apart_at_start" in s
    diff = pd.concat([rows("cassi-1.0", [("lips_apart_at_start", 2)]),
                      rows("cassi-2.0", [("lips_apart_at_start", 0), ("lips_overlap", 1)])])
    s = [x for x in R.version_summaries(diff) if "lip placement" in x][0]
    assert s.startswith("cassi-2.0 improves lip placement over cassi-1.0")
    assert "decided by lips_apart_at_start (0 against 2 negatives)" in s


def test_table_f_summary_names_the_worst_version():
    res = pd.concat([rows("parke-1974", [("fidelity_tongue_error", 2), ("fidelity_lips_error", 1)]),
                     rows("cassi-1.0", [("fidelity_tongue_error", 0), ("fidelity_lips_error", 0)])])
    s = R.version_summaries(res)
    assert any(x.startswith("Fidelity to the recording (cassi-farm's Table F): worst parke-1974 "
                            "with 3 negatives; best cassi-1.0 with 0 negatives") for x in s)


def test_history_totals_and_empty_inputs():
    res = pd.concat([rows("cassi-1.0", [("lips_apart_at_start", 1)]),
                     rows("cassi-2.0", [("lips_apart_at_start", 0)])])
    t = R.version_totals(res).set_index("version")["negatives"]
    assert t["cassi-1.0"] == 2 and t["cassi-2.0"] == 0       # Table A + Table C
    assert R.component_ratings(pd.DataFrame()).empty and R.verdicts(pd.DataFrame()).empty
    assert R.version_summaries(pd.DataFrame()) == []


def test_versions_whose_checks_agree_are_said_to_match_whatever_table_c_rule_added():
    """Table C charges each version against the one before it; two versions with the same
    negatives on every check 'match', and the sentence says where the totals' gap comes from."""
    from cassi.harness.rubric import tables as T

    v = pd.DataFrame({"version": ["b", "c"], "table": ["C", "C"], "check": ["lips_apart_at_start"] * 2,
                      "negatives": [2, 2]})
    both = T._per_check(v, "C", "b", "c")
    assert (both["a"] == both["b"]).all()
    note = T._rule_note(pd.Series({"b": 3}), "b", "c")
    assert note == " (every check agrees; Table C's comparison rule: b +3 against the version before it)"


def test_the_sentence_says_what_table_c_rule_added_when_every_check_agrees():
    """End to end: 2.0 fires in more shared files than 1.0 at the same rating (+1 against 1.0);
    2.1 has 2.0's negatives on every check, so it 'matches' 2.0 and the sentence names the +1."""
    res = pd.concat([_two_files("cassi-1.0", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 0)]),
                     _two_files("cassi-2.0", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 1)]),
                     _two_files("cassi-2.1", [("lips_apart_at_start", 1)], [("lips_apart_at_start", 1)])])
    assert cell(res, "C", "cassi-2.0")["adjust"] == 1 and cell(res, "C", "cassi-2.1")["adjust"] == 0
    s = [x for x in R.version_summaries(res) if "lip placement over cassi-2.0" in x][0]
    assert s.startswith("cassi-2.1 matches lip placement over cassi-2.0"), s
    assert "(every check agrees; Table C's comparison rule: cassi-2.0 +1 against the version " \
           "before it)" in s, s
