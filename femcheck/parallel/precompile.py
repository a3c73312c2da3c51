"""Compile the parallel-device chain kernels (:mod:`femcheck.parallel.chain_kernel`) into numba's on-disk cache.

numba compiles each ``@njit(cache=True)`` function on its first call and stores the machine code beside the module
(``__pycache__``, or ``NUMBA_CACHE_DIR``); a later process loads it in about 3 s instead of compiling for about
50 s of CPU. ``make venv`` runs this module once after installing, so that the first ``verify``, ``diagnose`` or
test run of a fresh install does not pay the compile, as a compiled extension is built when it is installed.

What runs is the set of calls that reaches every kernel specialization: the three reference devices (6-PSU,
hexapod, Delta), rigid and released joints, the fused kernel and the path from a solved leg state. The results
are discarded. ``python -m femcheck.parallel.precompile`` prints the number of compiled functions and the time.
"""
from __future__ import annotations

import time
from pathlib import Path

#: the reference devices whose evaluation reaches every kernel specialization (cases/ of this repository)
REFERENCE_CASES = ("haptic_6psu", "hexapod_6ups", "delta_3ruu")
#: an arbitrary non-degenerate TCP wrench (N, N m): every load branch of the kernels runs
_WRENCH = (1.0, 2.0, 10.0, 0.1, 0.0, 0.2)


def compile_kernels(cases_dir: Path | None = None) -> dict[str, int]:
    """Run the chain kernels once per specialization; {kernel function name: compiled signatures in this process}.

    A lazily compiled function loaded from the cache reports 0 signatures (one with an explicit signature reports
    it either way), so on an empty cache the counts are the specializations that exist.
    """
    from numba.core.registry import CPUDispatcher

    import femcheck.parallel.chain_kernel as kernel
    from femcheck.case import load_case
    from femcheck.chain import evaluate as chain_evaluate
    from femcheck.parallel.chain_model import evaluate
    from femcheck.parallel.device import test_points
    from femcheck.parallel.leg_kinematics import solve_legs

    cases_dir = cases_dir or Path(__file__).resolve().parents[2] / "cases"
    for name in REFERENCE_CASES:
        case = load_case(cases_dir / f"{name}.toml")
        poses = test_points(case)[:2]
        for joints in ("rigid", "released"):
            if name == "haptic_6psu":
                chain_evaluate(case, poses, list(_WRENCH), model="detailed", joints=joints)
            else:
                evaluate(case.device, poses, list(_WRENCH), joints=joints)                                   # fused
                evaluate(case.device, poses, list(_WRENCH), joints=joints, state=solve_legs(case.device, poses))
    return {k: len(f.signatures) for k, f in vars(kernel).items() if isinstance(f, CPUDispatcher)}


def main() -> int:
    start = time.perf_counter()
    counts = compile_kernels()
    print(f"chain kernels compiled or loaded from numba's cache: {len(counts)} functions in "
          f"{time.perf_counter() - start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
