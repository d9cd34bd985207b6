"""EMA (electromagnetic articulography) recordings read as XRMB task recordings.

- :mod:`.track` -- :class:`~.track.CoilTrack`, what every reader returns (named channels, times);
- :mod:`.est` -- Edinburgh Speech Tools track files (MOCHA-TIMIT, mngu0 ``.ema``);
- :mod:`.pos` -- Carstens AG500/AG501 ``.pos`` files;
- :mod:`.table` -- TSV/CSV exports with named columns (NDI Wave and others);
- :mod:`.coilmap` -- ``ema.yaml``: which coil plays which XRMB pellet, the references, presets;
- :mod:`.headframe` -- head correction (Kabsch) and the XRMB head frame, derived pellets;
- :mod:`.subject` -- one speaker directory's recordings as task recordings (used by
  :mod:`cassi.data.corpus.disk`);
- :mod:`.convert` -- ``cassi corpus convert``: an EMA corpus written as XRMB task files.
"""
