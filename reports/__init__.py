"""cassi.reports: thesis-style tables, the nightly version comparison and regression gates.
Reads harness results (files and the rubric registry) only."""
