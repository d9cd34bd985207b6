"""Basics every layer may import: errors that carry file and line (:mod:`.errors`), atomic
writes (:mod:`.atomic`) and command-line argument types (:mod:`.cliargs`). It imports no other
cassi package."""
