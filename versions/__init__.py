"""cassi.versions: CASSI 1.0, 2.0, 2.1 and the Parke baseline behind one protocol and a
registry. Imports cassi.data only."""
