"""A bar scene's parsed keys → a Bar (the third paper's impacting bar): its material,
area, the one obstacle at an end, the far end, the load and the initial profiles."""
from __future__ import annotations

from ..bar import Bar
from ..errors import InputError
from .parts import material_of, need, section_of
from .read import Tables


def _bar_area(d: dict) -> float:
    """A bar's [section]: its area A (m²), given as A or by a tube, rod or rect (a bar
    has no bending, so no I)."""
    from ..checks import check_positive
    forms = [k for k in ("tube", "rod", "rect", "A") if k in d]
    if len(forms) != 1 or "I" in d:
        raise InputError(f"a bar's [section] needs one of A, tube, rod, rect (got "
                         f"{', '.join(forms + (['I'] if 'I' in d else [])) or 'none'}; a bar "
                         "has no I)")
    if "A" in d:
        return check_positive("section.A", d["A"])
    return section_of(d, "section").A


def _bar_profile(d, name: str, value: str):
    if isinstance(d, dict):
        pairs = need(d, ("x", value), f"initial.{name}")
        if not isinstance(pairs["x"], list) or not isinstance(pairs[value], list) \
                or len(pairs["x"]) != len(pairs[value]):
            raise InputError(f"[initial.{name}] x and {value} must be arrays of one length")
        return list(zip(pairs["x"], pairs[value]))
    return d


def bar_problem(data: dict, reader: Tables) -> Bar:
    L = need(data.get("geometry", {}), ("L",), "geometry")["L"]
    mat = material_of(data.get("material", {}), "material", plausible=False)
    A = _bar_area(data["section"]) if "section" in data else None
    obstacles = data.get("obstacles", [])
    if len(obstacles) != 1 or "x" not in obstacles[0]:
        raise InputError("a bar needs one [[obstacles]] with x = 0 or x = L (the end it "
                         f"hits; stiffness = k for an elastic obstacle), got {len(obstacles)}")
    o = obstacles[0]
    ends = {"left": "free", "right": "free", **data.get("ends", {})}
    side = "left" if o["x"] in (0, "left") else "right"
    if ends[side] != "free":
        raise InputError(f"[ends] {side}={ends[side]!r}: the bar's obstacle is at that end, "
                         "which must be free (the far end is free or clamped)")
    loads = data.get("loads", [])
    if len(loads) > 1:
        raise InputError("a bar takes one [[loads]] value = f (a uniform body force, N/m³)")
    ini, mesh = data.get("initial", {}), data.get("mesh", {})
    law = data.get("contact", {}).get("law", "auto")
    try:
        return Bar(a=mat.E, b=data.get("damping", {}).get("viscosity", 0.0), rho=mat.rho, L=L,
                   f=loads[0].get("value", 0.0) if loads else 0.0,
                   v0=_bar_profile(ini.get("v0", 0.0), "v0", "v"),
                   u0=_bar_profile(ini.get("u0", 0.0), "u0", "u"),
                   obstacle="elastic" if "stiffness" in o and law != "penalty" else "rigid",
                   k=o.get("stiffness", 100.0), N=mesh.get("J", 100),
                   mass=mesh.get("mass", "average"), element=mesh.get("element", "p1"),
                   far_end=ends["right" if side == "left" else "left"], obstacle_at=o["x"],
                   A=A)
    except InputError as e:       # Bar's field names as the file's keys
        name, eq, rest = str(e).partition("=")
        if eq and name in BAR_FIELD_KEYS:
            raise InputError(f"{BAR_FIELD_KEYS[name]}={rest}") from None
        raise


# Bar's fields whose refusals name them (``N=0 must be …``), as a scene file writes them
BAR_FIELD_KEYS = {"N": "[mesh] J", "mass": "[mesh] mass", "element": "[mesh] element",
                  "k": "[obstacles.0] stiffness", "b": "[damping] viscosity",
                  "a": "[material] E", "rho": "[material] rho", "L": "[geometry] L",
                  "f": "[loads.0] value", "A": "[section] A"}
