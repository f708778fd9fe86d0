#!/usr/bin/env python3
"""The workspace's declared rust-version must be at least what every locked dependency
declares (cargo metadata over Cargo.lock): the packaging check of the test command."""
import json
import subprocess
import sys


def version(text):
    return tuple(int(part) for part in text.split("."))[:2]


metadata = json.loads(
    subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--locked"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
)
members = set(metadata["workspace_members"])
resolved = {node["id"] for node in metadata["resolve"]["nodes"]}
ours = {p["rust_version"] for p in metadata["packages"] if p["id"] in members}
if len(ours) != 1 or None in ours:
    sys.exit(f"every workspace crate must declare the one workspace rust-version, found {ours}")
declared = version(ours.pop())
needs = [
    (version(p["rust_version"]), p["name"], p["version"])
    for p in metadata["packages"]
    if p["id"] in resolved and p["id"] not in members and p.get("rust_version")
]
too_new = sorted(n for n in needs if n[0] > declared)
if too_new:
    listed = ", ".join(f"{name} {v} needs {r[0]}.{r[1]}" for r, name, v in too_new)
    sys.exit(f"rust-version {declared[0]}.{declared[1]} is below what the locked dependencies need: {listed}")
top = max(needs)
print(f"rust-version {declared[0]}.{declared[1]} covers every locked dependency (highest: {top[1]} {top[2]}, {top[0][0]}.{top[0][1]})")
