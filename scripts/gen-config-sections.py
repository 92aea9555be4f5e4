#!/usr/bin/env python3
"""Writes the [detect], [track], [control] and [sim] sections of config/hubtrack.toml from the code.

Values come from `hubtrack config --print` (the built-in defaults); the comment above each key is
the doc comment of its field in libs/<crate>/src/params.rs. Run after changing a parameter:
    cargo build --release -p hubtrack && scripts/gen-config-sections.py
The hand-written sections above the marker line are kept as they are.
"""
import re
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MARKER = "# ---- generated below by scripts/gen-config-sections.py from the parameter docs; edit the code, not this ----"
# section -> (source files holding its structs, top-level struct)
SECTIONS = {
    "detect": (["libs/detect/src/params.rs"], "DetectConfig"),
    "track": (["libs/track/src/params.rs"], "TrackConfig"),
    "control": (["libs/runtime/src/config.rs", "libs/approach/src/params.rs"], "ControlConfig"),
    "sim": (["libs/sim/src/params.rs"], "SimConfig"),
}


def parse_structs(text):
    """struct name -> list of (field, type, doc lines) and struct doc."""
    structs = {}
    for m in re.finditer(r"((?:\s*///[^\n]*\n)*)(?:\s*#\[[^\n]*\]\n)*\s*pub struct (\w+) \{(.*?)\n\}", text, re.S):
        sdoc = [l.strip()[3:].strip() for l in m.group(1).strip().splitlines() if l.strip().startswith("///")]
        fields = []
        doc = []
        for line in m.group(3).splitlines():
            s = line.strip()
            if s.startswith("///"):
                doc.append(s[3:].strip())
            elif s.startswith("pub "):
                fm = re.match(r"pub (\w+): ([^,]+),?", s)
                if fm:
                    fields.append((fm.group(1), fm.group(2).strip(), doc))
                doc = []
            elif s and not s.startswith("#") and not s.startswith("//"):
                doc = []
        structs[m.group(2)] = (sdoc, fields)
    return structs


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace('\\', '\\\\').replace('"', '\\"') + '"'
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return str(v)


def emit(out, path, struct, structs, values):
    sdoc, fields = structs[struct]
    out.append("")
    for l in sdoc:
        out.append(f"# {l}" if l else "#")
    out.append(f"[{path}]")
    nested = []
    for name, ty, doc in fields:
        base = ty.split("::")[-1]
        if base in structs:
            nested.append((name, base))
            continue
        for l in doc:
            out.append(f"# {l}" if l else "#")
        if name in values:
            out.append(f"{name} = {toml_value(values[name])}")
        else:
            out.append(f"# {name} = (unset)")
    for name, base in nested:
        emit(out, f"{path}.{name}", base, structs, values.get(name, {}))


def main():
    exe = ROOT / "target" / "release" / "hubtrack"
    defaults = tomllib.loads(subprocess.run([str(exe), "config", "--print"], check=True, capture_output=True, text=True).stdout)
    cfg = ROOT / "config" / "hubtrack.toml"
    head = cfg.read_text().split(MARKER)[0].rstrip("\n")
    out = [head, "", MARKER]
    for section, (sources, struct) in SECTIONS.items():
        structs = {}
        for src in sources:
            structs.update(parse_structs((ROOT / src).read_text()))
        emit(out, section, struct, structs, defaults[section])
    cfg.write_text("\n".join(out) + "\n")
    print(f"wrote {cfg}")


if __name__ == "__main__":
    sys.exit(main())
