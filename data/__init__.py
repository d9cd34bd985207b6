"""cassi.data: XRMB formats, preprocessing, the Parke-compatible face model and the
embedded synthetic corpus. The lowest layer: it imports no other cassi package."""
