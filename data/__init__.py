"""cassi.data: the lowest layer; it imports no other cassi package (but :mod:`cassi.common`).

Subpackages by concern:

- :mod:`.xrmb` -- the XRMB and Parke file formats and their validation;
- :mod:`.corpus` -- a corpus on disk, preprocessing (thesis 4.2) and kinematic statistics;
- :mod:`.face` -- the Parke-compatible face model;
- :mod:`.synth` -- the embedded synthetic corpus's generator.
"""
