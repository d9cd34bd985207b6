"""The automated rubric: every criterion of the thesis's evaluation (chapter 5, restated in
``shared/spec/rubric.md``) as one registered check, plus cassi-farm's Table F (fidelity to the
recording), and the one aggregation of check rows into the thesis's tables.

Modules by role:

- :mod:`.model` -- the check model (:class:`Check`, :class:`Measurement`) and the rating scale;
- :mod:`.geometry` -- pure geometric measures over vertex positions;
- :mod:`.measures` -- one geometric measure per check over an animation;
- :mod:`.image` -- measures on the renderer's part masks;
- :mod:`.fidelity` -- Table F: the model's pellet sites against the measured pellets;
- :mod:`.registry` -- every check, threshold, window and aggregation rule, with its reason;
- :mod:`.run` -- running checks into rows of the long results table;
- :mod:`.tables` -- the one aggregation into the thesis's tables.
"""
from cassi.harness.rubric.model import (GOOD_RATINGS, RATINGS, TABLE_TOPICS, TABLES, VERSION_ORDER, Check,
                    Measurement, rate, shown_beside, table_title)
from cassi.harness.rubric.registry import (AGGREGATION_RULES, CHECKS, MIN_FRAMES, checks_for, get_check,
                       registry_table)
from cassi.harness.rubric.measures import DIAGNOSTICS_READ
from cassi.harness.rubric.run import run_geometry_checks, run_image_checks
from cassi.harness.rubric.tables import (RATING_COLUMNS, component_ratings, ratings_table, file_verdicts, negatives_text, order_versions,
                     rating_counts, table_c_rule, verdicts, version_comparisons,
                     version_summaries, version_totals, table_totals, level_ratings, LEVEL_COLUMNS)

__all__ = [
    "Check", "Measurement", "CHECKS", "TABLES", "TABLE_TOPICS", "RATINGS", "GOOD_RATINGS",
    "VERSION_ORDER", "shown_beside", "MIN_FRAMES", "AGGREGATION_RULES", "rate", "table_title", "get_check",
    "checks_for", "registry_table", "DIAGNOSTICS_READ", "run_geometry_checks",
    "run_image_checks", "file_verdicts",
    "verdicts", "table_c_rule", "component_ratings", "rating_counts", "version_totals", "table_totals",
    "version_summaries", "version_comparisons", "negatives_text", "order_versions",
    "ratings_table", "RATING_COLUMNS", "level_ratings", "LEVEL_COLUMNS",
]
