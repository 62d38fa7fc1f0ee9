"""Python's cyclic garbage collector and ManiSkill's scene rebuilds.

ManiSkill ends every scene teardown (``BaseEnv._clear``, run by each reconfigure and by ``close``) with a full
``gc.collect()``, to release GPU memory. A full collection walks every object the collector tracks; with torch,
SciPy, trimesh and ManiSkill imported that is about 340 000 objects, 0.17 s on the reference 2-core machine, and the
solver rebuilds a scene for every grasp it tries in physics: a quarter of the time of collecting start states went
to those collections.

:func:`freeze_long_lived` moves what is alive before the first scene is built (modules, classes, import-time tables,
which live as long as the process) to the collector's permanent generation, so later collections walk only what was
made after: scenes, tensors, episodes. Scenes torn down later are still collected as before. The cost: a frozen
object that later ends up in an unreachable reference cycle is never reclaimed (the collection just before the freeze
leaves no garbage to freeze).
"""

from __future__ import annotations

import gc

_frozen = False


def freeze_long_lived() -> None:
    """Once per process: collect, then freeze every object tracked now (``gc.freeze``)."""
    global _frozen
    if _frozen:
        return
    gc.collect()
    gc.freeze()
    _frozen = True
