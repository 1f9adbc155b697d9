"""The plate's measured errors against exact solutions, printed as the tables of
docs/plate.md: ``python -m skfem_beam.plate.convergence`` (about 15 s)."""
import numpy as np

from .model import EDGES, Plate
from .modes import natural_frequencies
from .space import load_vector, plate_space
from .static import deflection_at_vertex, static_deflection

STATIC_MESHES = {"bfs": (4, 8, 16), "morley": (8, 16, 32), "argyris": (2, 4, 8)}
LEISSA_CLAMPED_SQUARE = 35.985      # ω a² √(ρh/D), all four edges clamped, ν = 0.3


def centre_deflection_error(element: str, n: int) -> float:
    """Simply supported unit square, p = sin(πx) sin(πy): exact w(½, ½) = 1/(4π⁴D)."""
    plate = Plate(element=element, nx=n, ny=n)
    space = plate_space(plate)
    f = load_vector(space, lambda x, y: np.sin(np.pi * x) * np.sin(np.pi * y))
    w = deflection_at_vertex(space, static_deflection(space, f), 0.5, 0.5)
    return abs(w * 4 * np.pi ** 4 * plate.D - 1.0)


def frequency_parameters(plate: Plate, count: int) -> np.ndarray:
    """ω / √(D/(ρh)) of the ``count`` lowest modes (1/m²)."""
    omega, _ = natural_frequencies(plate_space(plate), count)
    return omega / np.sqrt(plate.D / (plate.rho * plate.h))


def navier_table(a: float = 1.0, b: float = 0.6, meshes=(5, 10, 20)) -> None:
    """Simply supported a × b: ω_mn = π²(m²/a² + n²/b²) √(D/(ρh)), BFS on n × n."""
    exact = sorted((np.pi ** 2 * (m * m / a ** 2 + n * n / b ** 2), (m, n))
                   for m in range(1, 8) for n in range(1, 8))[:6]
    print(f"simply supported {a:g} x {b:g}, BFS: relative error of the six lowest ω")
    print("mesh     " + "  ".join(f"{str(mn):>8}" for _, mn in exact))
    previous = None
    for n in meshes:
        errors = frequency_parameters(Plate(a=a, b=b, nx=n, ny=n), 6) \
            / np.array([e for e, _ in exact]) - 1.0
        print(f"{n:2d} x {n:<2d}  " + "  ".join(f"{e:8.2e}" for e in errors))
        if previous is not None:
            print("  rate   " + "  ".join(f"{r:8.2f}" for r in np.log2(previous / errors)))
        previous = errors


def main(argv=None) -> None:
    import argparse     # no flags: --help says what it prints, a stray flag is refused
    argparse.ArgumentParser(prog="python -m skfem_beam.plate.convergence",
                            description=__doc__.split("\n\n")[0]).parse_args(argv)
    print("centre deflection, simply supported unit square, p = sin(πx) sin(πy)")
    for element, meshes in STATIC_MESHES.items():
        errors = [centre_deflection_error(element, n) for n in meshes]
        rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        print(f"  {element:8s} n = {meshes}: errors " + ", ".join(f"{e:.2e}" for e in errors)
              + "; rates " + ", ".join(f"{r:.2f}" for r in rates))
    navier_table()
    print(f"clamped square, ω a² √(ρh/D) against Leissa's {LEISSA_CLAMPED_SQUARE}")
    for element, n in [("bfs", 8), ("bfs", 10), ("bfs", 12), ("bfs", 20), ("argyris", 8)]:
        value = frequency_parameters(Plate(edges=dict.fromkeys(EDGES, "clamped"),
                                           element=element, nx=n, ny=n), 1)[0]
        print(f"  {element:8s} {n:2d} x {n:<2d} {value:.6f}  relative error "
              f"{value / LEISSA_CLAMPED_SQUARE - 1:.2e}")


if __name__ == "__main__":
    from ..cli import main_guard
    main_guard(main)
