"""The export formats by name and their file names (no heavy imports: the CLI's help reads them)."""

from __future__ import annotations

FILE_NAMES = {
    "iges": "hose.igs",
    "step": "hose.step",
    "stl": "hose.stl",
    "ply": "hose.ply",
    "gltf": "hose.glb",
    "adams": "hose.cmd",
}
ALIASES = {"igs": "iges", "stp": "step", "glb": "gltf", "cmd": "adams"}


def parse_formats(text: str) -> list[str]:
    """Format names from a comma-separated list such as "iges,step,stl" ("all" for every format).

    Accepts the file extensions igs, stp, glb and cmd as well, and "none" for no export.
    Raises ValueError naming an unknown format and listing the known ones.
    """
    names = []
    for word in (part.strip().lower() for part in text.split(",")):
        if word == "none":
            continue
        if word == "all":
            names.extend(FILE_NAMES)
        elif word in FILE_NAMES or word in ALIASES:
            names.append(ALIASES.get(word, word))
        elif word:
            raise ValueError(f"unknown export format {word!r}: choose from {', '.join(FILE_NAMES)} (or all, none)")
    return list(dict.fromkeys(names))
