"""Unit conversions used at the edges (files, configs, plots). Inside, everything is SI.

Names say the conversion: ``value_kn * KNOT_MPS`` is metres per second.
"""

from __future__ import annotations

#: one international knot in metres per second (1852 m per hour).
KNOT_MPS = 1852.0 / 3600.0
#: one kilometre in metres.
KM_M = 1000.0
#: one nautical mile in metres.
NMI_M = 1852.0
