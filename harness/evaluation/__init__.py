"""The CASSI evaluation on the farm: what a run is and what its jobs do.

- :mod:`.config` -- a run, declared (file or flags); :mod:`.evalset` -- the default task set;
- :mod:`.inputs` -- every corpus file a run reads, checked and digested before any job starts;
- :mod:`.provenance` -- the code and corpus digests a job's outputs depend on;
- :mod:`.frames` -- the frame policy: which frames a job renders, keeps and shows;
- :mod:`.caches` -- a worker's corpus, profiles, faces and renderers, kept across jobs;
- :mod:`.stages` -- the stages (geometry and checks, renders, image checks) and the pipeline;
- :mod:`.run` -- one run from a configuration; :mod:`.nightly` -- one night.
"""
