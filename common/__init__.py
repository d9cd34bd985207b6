"""Basics every layer may import: errors that carry file and line (:mod:`.errors`) and atomic
writes (:mod:`.atomic`). It imports no other cassi package."""
