#!/usr/bin/env python3
"""Writes a robot as MuJoCo itself saves it: the MJCF that MuJoCo's own writer gives for a
URDF or MJCF file (`MjSpec.to_xml`, what `mj_saveLastXML` writes), with the mesh directory
made absolute so that the saved file loads from anywhere. A URDF is read with its visuals kept
(`discardvisual="false"`) and MuJoCo's other URDF defaults: a base link that does not move is
fused into the world body, as MuJoCo does.

    python mujoco_save.py ROBOT.urdf|ROBOT.xml OUT.xml

Used by scripts/check_engines.sh to test `bvseg robot` on robots as MuJoCo saves them.
"""
import os
import re
import sys
import tempfile

import mujoco

from check_robot import resolve


def spec_of(path):
    if not path.lower().endswith(".urdf"):
        spec = mujoco.MjSpec.from_file(path)
        base = os.path.dirname(os.path.abspath(path))
        spec.meshdir = os.path.join(base, spec.meshdir)
        spec.texturedir = os.path.join(base, spec.texturedir)
        return spec
    text = open(path, encoding="utf-8").read()
    base = os.path.dirname(os.path.abspath(path))
    text = re.sub(r'filename="([^"]*)"', lambda m: f'filename="{resolve(base, m.group(1))}"', text)
    ext = '<mujoco><compiler strippath="false" discardvisual="false"/></mujoco>'
    text = re.sub(r"(<robot\b[^>]*>)", lambda m: m.group(1) + ext, text, count=1)
    with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False, encoding="utf-8") as f:
        f.write(text)
    try:
        return mujoco.MjSpec.from_file(f.name)
    finally:
        os.unlink(f.name)


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    spec = spec_of(sys.argv[1])
    spec.compile()
    with open(sys.argv[2], "w", encoding="utf-8") as f:
        f.write(spec.to_xml())
    return 0


if __name__ == "__main__":
    sys.exit(main())
