"""The Parke-compatible face model (thesis 3.1; Parke's dissertation).

- :mod:`.model` -- :class:`~.model.FaceModel` and :func:`~.model.build_face` (re-exported here);
- :mod:`.build`, :mod:`.surface`, :mod:`.mouth`, :mod:`.eyes`, :mod:`.layout` -- the generator;
- :mod:`.params` -- Parke's parameters (Table 3.1); :mod:`.numbering` -- vertex numbers;
- :mod:`.topology` -- the mirrored, triangulated render topology; :mod:`.preview` -- matplotlib.
"""
from cassi.data.face.model import *  # noqa: F401,F403 - `from cassi.data.face import FaceModel`
from cassi.data.face.model import __all__  # noqa: F401
