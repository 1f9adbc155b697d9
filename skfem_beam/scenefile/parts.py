"""What the builders of a beam and a bar share: the keys a table needs, a [section], a
[material] (a beam's checked for plausible units) and the number of bending planes."""
from __future__ import annotations

from ..errors import InputError
from ..problem import Material, Section


def need(d: dict, keys, where: str) -> dict:
    missing = [k for k in keys if k not in d]
    if missing:
        raise InputError(f"[{where}] needs {', '.join(keys)} (missing {', '.join(missing)})")
    return {k: d[k] for k in keys}


# beyond these a value is more likely in the wrong unit than a material (rubber to
# diamond; aerogel-free foams to osmium): one warning line, the run goes on
PLAUSIBLE = {"E": (1e6, 1.2e12, "Pa"), "rho": (10.0, 23000.0, "kg/m³")}


def material_of(d: dict, where: str, plausible: bool = True) -> Material:
    """[material] E, rho; a beam's outside PLAUSIBLE warns (a bar's may be the papers'
    dimensionless a = ρ = 1)."""
    material = in_section(where, Material, **need(d, ("E", "rho"), where))
    if plausible:
        warn_implausible(d, where)
    return material


def warn_implausible(d: dict, where: str) -> None:
    """One warning line for each of E, rho outside PLAUSIBLE (a beam's, a plate's)."""
    from ..cli import warn
    for key, (low, high, unit) in PLAUSIBLE.items():
        value = d[key]
        if not low <= value <= high:
            warn(f"[{where}] {key} = {value:g} {unit} is outside engineering materials "
                 f"({low:g}–{high:g} {unit}): is it in {unit}?")


def in_section(where: str, make, **values):
    """``make(**values)``, its error line naming the section (``[segments.1.material]
    E=0 must be > 0``: the line named only ``E``, whichever segment it was); a line that
    names it already is kept."""
    try:
        return make(**values)
    except InputError as e:
        if str(e).startswith(f"[{where}]"):
            raise
        raise InputError(f"[{where}] {e}") from None


def section_of(d: dict, where: str) -> Section:
    """A [section]: I and A, I_y, I_z and A (two planes: v along y bends with I_z, w
    along z with I_y), tube, rod or rect."""
    forms = [k for k in ("tube", "rod", "rect") if k in d] + (["I/A"] if set(d) & {
        "I", "A", "I_y", "I_z"} else [])
    if len(forms) != 1:
        raise InputError(f"[{where}] needs one of I and A, I_y, I_z and A, tube, rod, rect "
                         f"(got {', '.join(forms) or 'none'})")
    if "I_y" in d or "I_z" in d:
        if "I" in d:
            raise InputError(f"[{where}] give I (one plane) or I_y and I_z, not both")
        axes = need(d, ("I_y", "I_z", "A"), where)
        return in_section(where, Section, I=axes["I_z"], A=axes["A"], I_w=axes["I_y"])
    for form, keys in (("tube", ("outer_diameter", "wall")), ("rod", ("diameter",)),
                       ("rect", ("b", "h"))):
        if form in d:
            return in_section(f"{where}.{form}", getattr(Section, form),
                              **need(d[form], keys, f"{where}.{form}"))
    return in_section(where, Section, **need(d, ("I", "A"), where))


def plane_count(data: dict) -> int:
    planes = data.get("planes", 1)
    if planes not in (1, 2) or isinstance(planes, bool):
        raise InputError(f"planes = {planes!r} must be 1 or 2 (bending planes)")
    return int(planes)


def outer_radius(section: dict) -> float | None:
    """A tube's or rod's outer radius (m) from [section], else None."""
    diameter = section.get("tube", {}).get("outer_diameter") or \
        section.get("rod", {}).get("diameter")
    return None if diameter is None else 0.5 * diameter


SECTIONS = {"dt": "[time] ", "T": "[time] ", "load_window": "[time] ", "beta": "[time] ",
            "save_every": "[output] ", "frames": "[output] ", "solver": "[contact] "}


def named_section(e: InputError) -> InputError:
    """An error line ``key=value ...`` of a key of SECTIONS, with its section named."""
    message = str(e)
    return InputError(SECTIONS.get(message.split("=")[0], "") + message)


def stepping_of(t: dict, out: dict, **more):
    """The Stepping of [time] and [output], its error lines naming the section."""
    from ..scheme import Stepping
    try:
        return Stepping(t["dt"], t["T"], out["save_every"], out["frames"], **more)
    except InputError as e:
        raise named_section(e) from None
