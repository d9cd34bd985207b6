"""cassi.harness: the job model, caching and resumable execution (local or Ray), the
automated rubric and the command line. Imports cassi.data, cassi.versions, cassi.renderer."""
