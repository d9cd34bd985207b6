"""What ``cassi nightly`` renders by default (a light module: the CLI reads it at start-up)."""

#: What a night renders (all four views, raycast preview): the first frame and the two frames
#: the checks point at most strongly per task file and version; every NIGHTLY_ANIMATE_STRIDE-th
#: row of every task file in all four views for the video versions' four-view videos (real
#: time: 145.6 / stride frames per second), and in the front view for the other versions (the
#: view the image checks judge, on the same frames for every version; the side-by-side
#: comparisons). README says how the night's time was estimated from measured per-frame costs.
NIGHTLY_STRIDE = 0
NIGHTLY_EXTREMES = 2
NIGHTLY_ANIMATE_STRIDE = 24
#: The thesis's final version gets a four-view video of every task file.
NIGHTLY_VIDEO_VERSIONS = ("cassi-2.1",)
