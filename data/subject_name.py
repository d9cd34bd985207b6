"""A subject's name, the one rule for subject folders, the head-measures and profile files'
rows and ``--subjects`` lists: a letter, then up to 31 letters, digits, ``_`` or ``-`` (ASCII).

A module of its own, importing nothing of cassi, so that the command line's parsers can use
the rule without loading the file readers.
"""
import re

SUBJECT_NAME_RE = re.compile(r"[A-Za-z][A-Za-z0-9_-]{0,31}", re.ASCII)
