#!/usr/bin/env python3
"""Lists every #include that runs from a lower layer of penumbra to a higher one; prints nothing when the
layers only point down, and exits 1 when any include points up.

The layers, lowest first (docs/design.md): src/core -> src/scene -> src/render -> src/diff -> src/optim ->
src/studies -> app/ and python/. A file may include its own layer and the layers below it. Inside src/diff
the shared kit (the files at the top of the folder) is below the method folders (src/diff/<method>/): the kit
includes no method folder, and a method folder includes the kit and no other method folder, except those
named in METHOD_USES (a method built on another's pieces, e.g. war-bdpt on war's field).

    scripts/check_layers.py [REPO]      # REPO defaults to the checkout this script is in
"""
import os
import re
import sys

LAYERS = ["src/core", "src/scene", "src/render", "src/diff", "src/optim", "src/studies", "app", "python"]
RANK = {"src/core": 0, "src/scene": 1, "src/render": 2, "src/diff": 3, "src/optim": 4, "src/studies": 5,
        "app": 6, "python": 6}
# Method folders of src/diff that build on another method folder's pieces.
METHOD_USES = {
    "war": {"was"},  # paper 000 warps with paper 004's boundary test, warp field and auxiliary rays
}
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
SOURCE = (".h", ".hpp", ".cpp", ".cc")


def layer_of(path):
    """The layer of a repository-relative path, or None outside the layered code."""
    for layer in sorted(LAYERS, key=len, reverse=True):
        if path == layer or path.startswith(layer + "/"):
            return layer
    return None


def diff_part(path):
    """Inside src/diff: 'kit' for the top of the folder, else the method folder's name."""
    rest = path[len("src/diff/"):]
    return rest.split("/")[0] if "/" in rest else "kit"


def resolve(repo, including, target):
    """The repository-relative path an include names: relative to the including file's folder, else to src/."""
    local = os.path.normpath(os.path.join(os.path.dirname(including), target))
    if os.path.exists(os.path.join(repo, local)):
        return local
    for root in ("src", "."):
        p = os.path.normpath(os.path.join(root, target))
        if os.path.exists(os.path.join(repo, p)):
            return p
    return None


def upward_includes(repo):
    for layer in LAYERS:
        for folder, _, files in os.walk(os.path.join(repo, layer)):
            for name in sorted(files):
                if not name.endswith(SOURCE):
                    continue
                path = os.path.relpath(os.path.join(folder, name), repo)
                with open(os.path.join(repo, path), encoding="utf-8") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        target = resolve(repo, path, m.group(1))
                        to = layer_of(target) if target else None
                        if to is None:
                            continue
                        if RANK[to] > RANK[layer]:
                            yield f"{path}:{number}: {layer} includes {target} ({to}, a higher layer)"
                        elif layer == to == "src/diff":
                            a, b = diff_part(path), diff_part(target)
                            if a == b or b == "kit":
                                continue
                            if a == "kit":
                                yield f"{path}:{number}: the src/diff kit includes {target} (method folder {b})"
                            elif b not in METHOD_USES.get(a, set()):
                                yield f"{path}:{number}: method folder {a} includes {target} (method folder {b})"


def main():
    repo = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    found = list(upward_includes(os.path.abspath(repo)))
    for line in found:
        print(line)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
