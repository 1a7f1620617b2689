"""The simulate system's settings: one tree, the scene's (sim/scene.py :class:`PassiveSceneSettings`).

``sonartrack simulate --print-config`` prints it: the recording (duration, sample rate, band, noise level)
and the medium (the sound speed, declared once at the root) at the root; ``[ownship]``, ``[array]``,
``[[ships]]`` and ``[samples]`` hold what is their own. The system overrides no default of the scene, so the
tree is the scene's class itself.
"""

from __future__ import annotations

from sonartrack.sim.scene import PassiveSceneSettings

__all__ = ["PassiveSceneSettings"]
