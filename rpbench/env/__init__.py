"""rpbench as a Gymnasium environment for learning dispatchers: ``gymnasium.make("rpbench/Dispatch-v0")``
once ``rpbench.env`` is imported (docs/gym.md).  Needs the ``env`` extra (``pip install 'rpbench[env]'``)."""

from __future__ import annotations

try:
    import gymnasium
except ImportError as exc:  # the one line a user without the extra sees
    raise ImportError("rpbench.env needs Gymnasium: pip install 'rpbench[env]'") from exc

from rpbench.env.dispatch import DispatchEnv

ENV_ID = "rpbench/Dispatch-v0"

if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="rpbench.env.dispatch:DispatchEnv")

__all__ = ["ENV_ID", "DispatchEnv"]
