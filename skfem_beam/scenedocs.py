"""What every key of a scene file means: the text of the reference the documentation
generates (docs/scene_files.md includes :func:`reference`), one entry per section of
:data:`skfem_beam.scenefile.schema.BEAM_KEYS` and
:data:`~skfem_beam.scenefile.schema.BAR_KEYS`.

The keys themselves are read from those tables, so a key added to the code appears in the
docs; tests/test_docs.py fails when a key is not named in its section's text here.
"""
from __future__ import annotations

SECTION_DOCS = {
    '(top level)': (
        '`kind = "beam"` (default) or `"bar"`; `planes = 2`: a beam bending in two planes, v '
        'along y and w along z (below)'
    ),
    'material': (
        '`E`, `rho`'
    ),
    'section': (
        '`I`, `A`, or `I_y`, `I_z`, `A` (v along y bends with I_z, w along z with I_y), or '
        '`tube = {outer_diameter, wall}`, `rod = {diameter}`, `rect = {b, h}` (h along y; '
        'bar: optional, then forces in N)'
    ),
    'mass_normalised': (
        "`k2` (EI/ρA, m⁴/s²), `rho_S` (kg/m): the papers' form, instead of material and "
        'section'
    ),
    'mass': (
        '`added` (kg/m): mass carried along the whole beam, e.g. the fluid inside and around '
        'a tube (its hydrodynamic mass); ρA + added is the inertia, and converts forces to N; '
        'gravity and `per_mass` loads act on ρA + added too (a fluid round the tube, which '
        'its buoyancy holds up, adds no weight: give the weight as a `distributed` load)'
    ),
    'geometry': (
        '`L` (m)'
    ),
    'ends': (
        '`left`, `right`: `clamped` \\| `pinned` \\| `sliding` \\| `free` (default clamped–free;'
        ' bar: the far end free or clamped)'
    ),
    'supports': (
        '`x`: a rigid pinned support'
    ),
    'motion': (
        '`end = "left"\\|"right"` or `at = x` (a support); `amplitude`, `omega` (φ = A sin ωt)'
        ' or `sines = [[A, ω, phase], ...]`, `table = "phi.csv"` (t, φ rows: a cubic '
        'spline through them, held at its first and last values outside them; a warning '
        'when it ends before T or the spline overshoots its rows), '
        '`random = {rms,'
        ' f_low, f_high, seed, count}` (band-limited, `count` sines), `psd = { table, seed, df }`, `value` '
        '(constant), as for loads; `phase` with `amplitude`, `omega`; `lifting = "auto"` '
        '(default), `"paper"` (the first paper\'s h(x): a clamped end at x = 0, the other '
        'free or pinned, a uniform beam without supports) or `"static"` (h the discrete '
        'static shape with u = 1 at the moving support): how u is split into h(x)φ(t) and '
        'the rest, which changes no result beyond round-off and the time discretisation; '
        'two planes: '
        '`direction = [dy, dz]` (a direction: its length is not used)'
    ),
    'obstacles': (
        '`x` (point stops) or `x_from`, `x_to` (a span) or neither (the whole beam); `g1`, '
        '`g2`: numbers, `{ poly = [c0, c1, ...], about = x0 }` (Σ c_k (x − x0)^k) or `{ x = '
        '[...], g = [...] }` (linear between points, covering where it acts); `carried = '
        'true` moves with the support; `stiffness` (N/m) and `damping` (N·s/m, optional): elastic supports, the '
        "penalty law's springs with Kelvin–Voigt dashpots (k·δ + c·δ' while the spring is "
        "compressed: on the rebound the dashpot can pull, as a linear one does), each "
        "obstacle its own (one plane; "
        'two planes: the same on every obstacle), on every obstacle or none (rigid); '
        "summary.json `spring_supports` gives each one's largest deflection and force. "
        'Two planes: g1, g2 bound v; `hole = {...}` at `x` or over `x_from`, `x_to` bounds '
        '(v, w) of the beam\'s axis, so every size is a clearance, not the hole\'s own: '
        '`{ radius = r }` (drilled: r the radial clearance, e.g. 0.0004 for 0.4 mm; '
        '`centre = [cy, cz]` optional), `{ sides = n, '
        'radius = r, angle = a }` (a regular polygon, r to its faces, a in rad: beyond a '
        'turn it is warned of as degrees), `{ lands = '
        'n, land_width = deg, radius = r, angle = deg }` (broached: n lands, arcs of the '
        'circle of radius r each land_width degrees wide, centred at angle + 360k/n degrees, '
        'open lobes between them: a trefoil is 3, a quatrefoil 4; lands of no width are '
        'the polygon `{ sides = n }`), `{ '
        'polygon = [[y, z], ...] }` (convex, counter-clockwise), `{ faces = [[ny, nz, gap], '
        '...] }` (flat bars: n·(v, w) ≤ gap); `friction` (μ at this hole, overriding '
        '`[contact] friction`; refused at a hole that moves with the support\'s motion, '
        'carried or fixed under a `[motion]`: its slip is not yet taken relative to the '
        'hole). An obstacle at a node the ends or supports hold is refused '
        '(it would bound nothing). Bar: one, `x = 0` or `L`, `stiffness` for an elastic '
        'obstacle.'
    ),
    'damping': (
        '`zeta`, `f1`, `f2` (Hz) or `alpha`, `alpha_K` (Rayleigh), or `modal = ζ` (every mode'
        ' at ζ: a dense damping matrix); ζ is a ratio below 1 (0.02 for 2 %); under a '
        '[motion] it damps the motion relative to the support\'s quasi-static one, whatever '
        'the lifting; bar: '
        '`viscosity` (Kelvin–Voigt b)'
    ),
    'loads': (
        '`x` (a point force, N) or `distributed = true` (N/m) or `per_mass = true` (m/s², the'
        " papers' f̃) or `gravity = 9.81`; the time: `amplitude`, `omega` (rad/s), `phase` "
        '(rad): amplitude·sin(ωt + phase), `value`, `sines`, '
        '`table = "f.csv"` (a cubic spline through its rows, held at its first and last '
        'values outside its times; a warning when it ends before T or the spline overshoots '
        'its rows), '
        '`random = {rms, f_low, f_high, seed, count}`, `psd = "S.csv"` or '
        '`psd = { table = "S.csv", seed = 1, df = 0.1 }` (a one-sided PSD, columns f in Hz '
        'and S in N²/m²/Hz for a distributed force, synthesised with the seed: '
        '`timefunctions.from_psd`); a distributed load over part of the beam: `x_from`, '
        '`x_to` (exact when they are nodes); two planes: `direction = [dy, dz]` (a direction: '
        'its length is not used; default the first plane; gravity pulls along it, and '
        'without it down in the first plane), or `rotating = {amplitude, '
        'omega, phase}` instead of a time function (amplitude·cos(ωt + phase) along y, '
        '·sin along z). Bar: `value` (a body force, N/m³)'
    ),
    'initial': (
        '`mode = k` with `amplitude` (m; u0 = amplitude × the k-th mode shape, its largest '
        '\\|u\\| 1) '
        'or `u0 = {x = [...], u = [...]}` (cubic spline; bar: linear, or a number), `v0 = {x, '
        "v}`; two planes: these are the first plane's, `u0_w = {x, u}`, `v0_w = {x, v}` the "
        "second's (without them w starts at rest); beams read them in the fixed frame (ũ, "
        'ũ_t) unless `fixed_frame = false`: no `[initial]` is at rest on the supports (a '
        'support displaced at t = 0 carries the beam in its static shape there); a `u0` '
        'that misses a clamped or pinned end or a support is refused'
    ),
    'mesh': (
        '`J` (elements, default 19; a node must fall on every obstacle end, support and '
        'segment step), `element = "hermite"\\|"bspline"`, `nodes = [...]` (non-uniform), `mass = '
        '"consistent"\\|"redistributed"`; bar: `J` (elements), `mass = '
        '"average"\\|"consistent"\\|"lumped"\\|"redistributed"`, `element = "p1"\\|"p2"` '
        '(Lagrange degree 1, the default, or 2; as `--element`); both: `massless = '
        '"beta"\\|"quasi-static"` (only with `mass = "redistributed"`, as `--massless`)'
    ),
    'time': (
        '`dt`, `T` (required), `beta` (the β-scheme\'s: default 1/2; 1/4 for a bar or '
        'penalty; `law = "moreau-jean"` has θ instead and does not use it), `load_window` '
        '(`"forward"`, the papers\': fⁿ averages f over [tₙ, tₙ + Δt]; `"centered"`: over [tₙ '
        '− Δt/2, tₙ + Δt/2], second order)'
    ),
    'contact': (
        "`law`: `position` (default, the papers' scheme; or one of its solvers `auto`, "
        '`projection`, `active-set`, `osqp`, `daqp`, `round-hole`), `moreau-jean`, `penalty` '
        '(as `--law`); round holes take `auto` (the exact round-hole law) or `penalty` '
        '(radial springs); `stiffness` (N/m, the penalty spring), `restitution` (e in [0, 1],'
        ' position and moreau-jean), `theta` (θ in [1/2, 1] of moreau-jean, default 1/2; '
        "as `--theta`), `friction` (Coulomb's μ at the holes' walls, two planes: `auto` "
        'then runs the exact round-hole-friction law, in round holes and on faces; '
        '`moreau-jean` as a choice); and the parameters of the law named, from its own table (a '
        "registered law's, as `--param NAME=VALUE`)"
    ),
    'output': (
        '`format`, `save_every`, `frames`, `flush_every`, `checkpoint_every`, `probes` (x in '
        'm, e.g. `[0.5, 0.75]`: probe columns as `--probe`, which `run` also takes)'
    ),
    'segments': (
        'a stepped beam instead of `[geometry]`: one `[[segments]]` per part, left to right, '
        'with `length`, `material = {E, rho}`, `section = {...}` (as `[section]`), each its '
        'own (no shared `[material]`); the mesh needs a node at every step (`[mesh] J`)'
    ),
    'wear': (
        "Archard's law at the holes (two planes): `coefficient` K (m³/(N·m)), "
        "`service_years`, `land` (the support's axial width b, m; optional: a depth needs it),"
        " `radius` (the tube's outer radius, m; default from a tube or rod `[section]`; only"
        " the depth needs it); summary.json's supports get the wear volume rate and volume,"
        ' per support and per 30° sector, and with `land` the depth spread evenly and per'
        ' sector; the rates are averaged over the whole run, its start included, then '
        'carried over the service years: run long enough for the start not to count'
    ),
}


def _keys(schema, prefix: str = "") -> list[str]:
    """The section's keys, nested tables as table.key."""
    out = []
    for key, sub in schema.items():
        out.append(prefix + key)
        sub = sub[0] if isinstance(sub, list) else sub
        if isinstance(sub, dict):
            out += _keys(sub, prefix + key + ".")
    return out


def sections() -> dict[str, dict[str, list[str]]]:
    """section → {"beam": keys, "bar": keys} ("(top level)": the scalar keys)."""
    from .scenefile.schema import BAR_KEYS, BEAM_KEYS
    out: dict[str, dict[str, list[str]]] = {}
    for kind, schema in (("beam", BEAM_KEYS), ("bar", BAR_KEYS)):
        for key, sub in schema.items():
            inner = sub[0] if isinstance(sub, list) else sub
            if isinstance(inner, dict) and not type(inner).__name__ in ("Either", "NumberOr"):
                out.setdefault(key, {})[kind] = _keys(inner)
            else:
                out.setdefault("(top level)", {}).setdefault(kind, []).append(key)
    return out


def reference() -> str:
    """The scene-file reference as a Markdown table: section, its keys (from the code),
    what they mean."""
    from .scenefile.schema import BAR_KEYS, BEAM_KEYS
    rows = ["| section | keys (from the code) | what they mean (SI units) |", "|---|---|---|"]
    for name, kinds in sections().items():
        array = isinstance(BEAM_KEYS.get(name, BAR_KEYS.get(name)), list)
        label = name if name == "(top level)" else (f"`[[{name}]]`" if array else f"`[{name}]`")
        keys = "; ".join(f"{kind}: " + ", ".join(f"`{k}`" for k in ks)
                         for kind, ks in kinds.items())
        rows.append(f"| {label} | {keys} | {SECTION_DOCS[name]} |")
    return "\n".join(rows) + "\n"


PAGE = "docs/scene_keys.md"     # relative to the repository


def page() -> str:
    """docs/scene_keys.md: :func:`reference` under its heading (tests/test_docs.py checks
    that the committed page is this text, so that it reads on GitHub as the code is)."""
    return ("# Scene-file keys\n\n"
            "Every section and key of a beam's or a bar's scene file, read from the code's own "
            "tables\n(`skfem_beam.scenefile.BEAM_KEYS`, `BAR_KEYS`; the texts are "
            "`skfem_beam.scenedocs`,\nand a test fails when a key has none or this page is "
            "not the code's). A plate's keys:\n[plate.md](plate.md). Rewritten by the docs "
            "build.\n\n" + reference())
