"""rpbench: an optimisation-modelling benchmark suite for dynamic ride-pooling dispatch.

Implements Wang, Yang, Feng, Hu, He, "A prediction-based forward-looking
vehicle dispatching strategy for dynamic ride-pooling" on the real Haikou
road network and DiDi orders.  ``import rpbench`` loads no solver library.
"""

__version__ = "0.1.0"
