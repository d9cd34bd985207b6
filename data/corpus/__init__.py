"""A corpus on disk and what is computed from it.

- :mod:`.disk` -- :class:`~.disk.Corpus`: subject directories, task files, usability, checks;
- :mod:`.profile` -- per-subject preprocessing for CASSI 2.x (thesis 4.2.1, 4.2.3, App. B);
- :mod:`.stats` -- kinematic statistics (``cassi corpus stats``).
"""
