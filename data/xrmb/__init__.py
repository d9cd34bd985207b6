"""The XRMB and Parke file formats CASSI reads, with their validation (thesis chapter 3).

- :mod:`.files` -- task files (``.txy``), ``PAL.DAT`` / ``PHA.DAT`` (and, re-exported, the
  readers of the two modules below);
- :mod:`.mis` -- ``Mis.dat``; :mod:`.headmeasures` -- gonion and gnathion;
- :mod:`.frames` -- frame sets: pellet frames without times (``.npy``, ``.mat``);
- :mod:`.parke_io` -- Parke's ``st1.pts`` / ``stt.top``; :mod:`.alignment` -- TextGrids;
- :mod:`.textlines` -- the small whitespace-separated formats' shared line reader.
"""
from cassi.data.xrmb.files import *  # noqa: F401,F403 - the readers, as `cassi.data.xrmb.read_txy`
from cassi.data.xrmb.files import __all__  # noqa: F401
