"""The float parameter vector the Numba integrators read (one index per name)."""

from __future__ import annotations

import numpy as np

__all__ = ["NAMES", "pack"]

NAMES = (
    "a",  # bead radius [µm]
    "kind",  # pillar kind (contact.ROUGH / SMOOTH)
    "r_cut",  # contact cutoff R_ref [µm]
    "r_eq",  # distance where |F| = F_ref [µm]
    "f_ref",  # contact force scale [pN]
    "vscale",  # factor on the background velocity
    "mu_f",  # friction coefficient
    "hyd_s",  # pillar wall-drag strength (multiplier on the Faxén drag)
    "hyd_l",  # its screening length [µm]
    "kT",  # thermal energy [pN µm]
    "max_disp",  # largest bead move per step far from the pillar [µm]
    "contact_disp",  # largest bead move per step near the pillar [µm]
    "dt_max",  # largest step [s]
    "t_max",  # give up [s]
    "x_stop",  # stop when the rearmost bead passes this x [µm] (mode 0)
    "t_stop",  # stop at this time [s] (mode 1)
    "mode",  # 0: run until past the pillar, 1: run until t_stop
    "trap_speed",  # COM speed below which a fiber in contact is stopped [µm/s]
    "trap_time",  # stopped this long -> trapped [s]
    "y_lo",  # bead centres must stay above [µm]
    "y_hi",  # and below [µm]
    "dt",  # bead-spring fixed step [s]
    "stretch",  # bead-spring S [pN]
    "bend",  # bead-spring B [pN µm²]
    "mu",  # viscosity [pN s/µm²]
)
IDX = {name: i for i, name in enumerate(NAMES)}

P_A = 0
P_KIND = 1
P_R_CUT = 2
P_R_EQ = 3
P_F_REF = 4
P_VSCALE = 5
P_MU_F = 6
P_HYD_S = 7
P_HYD_L = 8
P_KT = 9
P_MAX_DISP = 10
P_CONTACT_DISP = 11
P_DT_MAX = 12
P_T_MAX = 13
P_X_STOP = 14
P_T_STOP = 15
P_MODE = 16
P_TRAP_SPEED = 17
P_TRAP_TIME = 18
P_Y_LO = 19
P_Y_HI = 20
P_DT = 21
P_STRETCH = 22
P_BEND = 23
P_MU = 24

# The kernels read the P_* constants (Numba needs them as plain globals); keep
# them in step with NAMES, which pack() fills.
_WRONG = [n for n in NAMES if globals().get(f"P_{n.upper()}") != IDX[n]]
if _WRONG:
    raise ImportError(f"kparams: P_* constants out of step with NAMES for {_WRONG}")


def pack(**values: float) -> np.ndarray:
    """Float64 vector with every name in NAMES set (missing names: NaN)."""
    unknown = set(values) - set(NAMES)
    if unknown:
        raise KeyError(f"unknown kernel parameters: {sorted(unknown)}")
    out = np.full(len(NAMES), np.nan)
    for k, v in values.items():
        out[IDX[k]] = float(v)
    return out
