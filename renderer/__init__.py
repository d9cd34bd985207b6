"""cassi.renderer: Mitsuba 3 batch rendering of face mesh sequences from the front, side,
half-face and top-of-palate views, with masks for image metrics. Imports cassi.data only."""
