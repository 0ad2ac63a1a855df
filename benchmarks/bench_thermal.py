"""Speed and accuracy of thermal.simulate against scipy.integrate.solve_ivp.

Run as ``python benchmarks/bench_thermal.py``.  The case: a representative 7-node north
finder (docs/physics.md section 2 defaults, written out below), 7 start-up runs of 9000 s sampled
at 1 Hz from T0 in (-32, -16, -5, 17, 28, 43, 54) C, chamber held at T0, with the TEC law of
the light source P_tec(T_e) = 0.03 max(0, 25 - T_e) + 0.07 max(0, T_e - 25) [W].

thermal.simulate evaluates the TEC law at each 1 s sample and holds it over the step (zero-
order hold, ZOH); solve_ivp evaluates it continuously.  The two therefore solve slightly
different problems, so the benchmark reports:

1. wall time of the 7 runs: ours, and solve_ivp RK45 (rtol 1e-8, atol 1e-10) with the
   continuous TEC law, and with the same ZOH law (one solve_ivp call per 1 s step);
2. accuracy against tight references (DOP853, rtol 1e-13, atol 1e-12), continuous and ZOH:
   our error against the ZOH reference is the solver error, against the continuous one it is
   the cost of holding the TEC power for 1 s.
The tight ZOH reference (one DOP853 call per step) costs seconds per run, so it is computed
for the two extreme T0 only.  Both ZOH solvers sit at the round-off level there.

Why continuous RK45 is fast here: once the 1-8 min component transients have died, its step
is bounded only by stability (about 3 x the shortest time constant), so a 9000 s run takes
~80 steps and its t_eval output is interpolated; thermal.simulate must call the Python TEC
law at each of the 9000 samples by construction (held power), which sets its cost.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from thermal import CHAMBER, Link, Network, Node, simulate, simulate_many

T0_C = (-32.0, -16.0, -5.0, 17.0, 28.0, 43.0, 54.0)
TIME_S = np.arange(0.0, 9001.0, 1.0)
RK45 = dict(method="RK45", rtol=1e-8, atol=1e-10)
TIGHT = dict(method="DOP853", rtol=1e-13, atol=1e-12)
# over a whole run DOP853 takes steps of minutes; its dense output (t_eval) would then err by
# ~1e-7 K, so the continuous reference is held to steps of at most 5 s
TIGHT_CONTINUOUS = dict(TIGHT, max_step=5.0)

NETWORK = Network(
    nodes=(
        Node("housing", 3500.0),                # housing and base
        Node("electronics", 200.0, 3.0),        # FOG electronics, light source, TEC
        Node("board", 250.0, 5.0),              # main board and turntable driver
        Node("coil_outer", 70.0),               # outer fiber layers
        Node("coil_inner", 140.0),              # inner fiber layers with the spool
        Node("qfa_x", 45.0, 0.45),
        Node("qfa_y", 45.0, 0.45),
    ),
    links=(
        Link("housing", CHAMBER, 2.2),
        Link("electronics", "housing", 1.0),
        Link("board", "housing", 1.5),
        Link("coil_outer", "housing", 0.6),
        Link("coil_inner", "housing", 0.3),     # through the spool
        Link("coil_outer", "coil_inner", 0.25),
        Link("electronics", "coil_outer", 0.3),
        Link("qfa_x", "housing", 0.5),
        Link("qfa_y", "housing", 0.5),
    ),
)
N = len(NETWORK.nodes)
J_TEC = NETWORK.index("electronics")


def tec_power_w(t_s: float, temperature_c: np.ndarray) -> np.ndarray:
    """Extra power of the TEC holding the light source at 25 C [W] per node."""
    p = np.zeros(N)
    te = temperature_c[J_TEC]
    p[J_TEC] = 0.03 * max(0.0, 25.0 - te) + 0.07 * max(0.0, te - 25.0)
    return p


def tec_power_many_w(t_s: float, temperature_c: np.ndarray) -> np.ndarray:
    """:func:`tec_power_w` for R runs at once, temperatures (R, N) -> powers (R, N) [W]."""
    p = np.zeros(temperature_c.shape)
    te = temperature_c[:, J_TEC]
    p[:, J_TEC] = 0.03 * np.maximum(0.0, 25.0 - te) + 0.07 * np.maximum(0.0, te - 25.0)
    return p


A, B = NETWORK.matrices()
B_AMB, B_P = B[:, 0], B[:, 1:]
P_NODE = NETWORK.node_power_w


def ours(t0: float) -> np.ndarray:
    return simulate(NETWORK, TIME_S, ambient_c=t0, initial_c=t0,
                    power_w=tec_power_w).temperature_c


def ivp_continuous(t0: float, options: dict) -> tuple[np.ndarray, int]:
    """solve_ivp with the TEC law evaluated continuously; (temperatures, rhs evaluations)."""
    def rhs(t_s, temp):
        return A @ temp + B_AMB * t0 + B_P @ (P_NODE + tec_power_w(t_s, temp))
    sol = solve_ivp(rhs, (TIME_S[0], TIME_S[-1]), np.full(N, t0), t_eval=TIME_S, **options)
    return sol.y.T, sol.nfev


def ivp_held(t0: float, options: dict) -> np.ndarray:
    """solve_ivp over each 1 s step with the TEC power of the step's start held (ZOH)."""
    temp = np.empty((TIME_S.size, N))
    temp[0] = t0
    for k in range(TIME_S.size - 1):
        drive = B_AMB * t0 + B_P @ (P_NODE + tec_power_w(TIME_S[k], temp[k]))
        sol = solve_ivp(lambda t_s, x: A @ x + drive, (TIME_S[k], TIME_S[k + 1]), temp[k],
                        **options)
        temp[k + 1] = sol.y[:, -1]
    return temp


def timed(fn, *args):
    start = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - start


def main() -> None:
    ours(T0_C[0])                                  # warm-up (imports, first expm)
    repeats = [timed(lambda: [ours(t0) for t0 in T0_C]) for _ in range(3)]
    t_ours = min(r[1] for r in repeats)
    mine = repeats[0][0]
    linear = min(timed(lambda: [simulate(NETWORK, TIME_S, ambient_c=t0, initial_c=t0)
                                for t0 in T0_C])[1] for _ in range(3))
    starts = np.array(T0_C)
    (stacked, t_many) = min((timed(lambda: simulate_many(
        NETWORK, TIME_S, ambient_c=np.repeat(starts[:, None], TIME_S.size, axis=1),
        initial_c=starts, power_w=tec_power_many_w)) for _ in range(3)), key=lambda r: r[1])

    (cont, t_cont) = timed(lambda: [ivp_continuous(t0, RK45) for t0 in T0_C])
    nfev = sum(c[1] for c in cont)
    cont = [c[0] for c in cont]
    (held, t_held) = timed(lambda: [ivp_held(t0, RK45) for t0 in T0_C])
    ref_cont = [ivp_continuous(t0, TIGHT_CONTINUOUS)[0] for t0 in T0_C]

    def worst(xs, ys):
        return max(float(np.max(np.abs(x - y))) for x, y in zip(xs, ys))

    steps = TIME_S.size - 1
    print(f"case: 7-node network, {len(T0_C)} runs x {steps} steps of 1 s, TEC law in Python")
    print(f"thermal 7 runs: {t_ours:.3f} s ({t_ours / len(T0_C) * 1e3:.1f} ms/run, "
          f"{t_ours / len(T0_C) / steps * 1e6:.2f} us/step, best of 3); "
          f"without the TEC law (vectorised path): {linear:.3f} s")
    print(f"thermal 7 runs stacked (simulate_many, one march for all): {t_many:.3f} s "
          f"({t_many / len(T0_C) * 1e3:.1f} ms/run); max |dT| vs the runs alone "
          f"{worst(mine, [r.temperature_c for r in stacked]):.1e} K")
    ratio = t_cont / t_ours
    print(f"solve_ivp RK45 rtol 1e-8, continuous TEC: {t_cont:.3f} s ({nfev} rhs calls in all); "
          f"ratio {ratio:.1f}x; max |dT| vs thermal {worst(mine, cont):.1e} K "
          f"(thermal holds the TEC power for 1 s)")
    print(f"solve_ivp RK45 rtol 1e-8, same ZOH TEC (one call per step): {t_held:.2f} s; "
          f"ratio {t_held / t_ours:.0f}x; max |dT| vs thermal {worst(mine, held):.1e} K")
    print(f"target 'thermal >= 20x faster than continuous RK45': "
          f"{'met' if ratio >= 20 else 'NOT met'} ({ratio:.1f}x); against RK45 on the same "
          f"held problem: {t_held / t_ours:.0f}x")

    print("accuracy against DOP853 rtol 1e-13 (max |dT| over the runs compared):")
    print(f"  continuous reference, 7 runs: thermal {worst(mine, ref_cont):.1e} K "
          f"(the 1 s hold of the TEC power), RK45 continuous {worst(cont, ref_cont):.1e} K")
    extremes = [0, len(T0_C) - 1]
    ref_held = [ivp_held(T0_C[i], TIGHT) for i in extremes]
    print(f"  held (ZOH) reference, T0 = {T0_C[0]:g} and {T0_C[-1]:g} C: thermal "
          f"{worst([mine[i] for i in extremes], ref_held):.1e} K, RK45 same ZOH "
          f"{worst([held[i] for i in extremes], ref_held):.1e} K")


if __name__ == "__main__":
    main()
