"""The embedded synthetic corpus (no real XRMB data can ship).

- :mod:`.corpus` -- plans, generates and caches the corpus (:func:`~.corpus.default_corpus`);
- :mod:`.subjects` -- per-subject figures with their sources; :mod:`.tasks` -- the protocol;
- :mod:`.program` -- what happens when in a task; :mod:`.motion` -- the articulatory trajectories.
"""
