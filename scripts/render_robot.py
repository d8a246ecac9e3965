#!/usr/bin/env python3
"""Renders an MJCF robot (such as `bvseg robot`'s <robot>.xml) to a PNG with MuJoCo's
offscreen renderer, every geom group shown, on white, cropped to the robot.

    MUJOCO_GL=egl python render_robot.py ROBOT.xml OUT.png [--qpos "q1 q2 ..."]
        [--lookat X Y Z] [--distance D] [--azimuth A] [--elevation E]

Needs MuJoCo's Python package, numpy, Pillow, and an OpenGL that works without a display
(MUJOCO_GL=egl or osmesa). docs/images/robot-panda.png was made with it (docs/robots.md).
"""
import argparse

import mujoco
import numpy as np
from PIL import Image


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mjcf")
    ap.add_argument("png")
    ap.add_argument("--qpos", default="", help="the first joint positions, space-separated")
    ap.add_argument("--lookat", type=float, nargs=3, default=[0.25, 0.0, 0.45])
    ap.add_argument("--distance", type=float, default=1.25)
    ap.add_argument("--azimuth", type=float, default=135.0)
    ap.add_argument("--elevation", type=float, default=-20.0)
    a = ap.parse_args()
    m = mujoco.MjModel.from_xml_path(a.mjcf)
    m.vis.global_.offwidth, m.vis.global_.offheight = 900, 700
    m.vis.headlight.ambient[:] = [0.45] * 3
    m.vis.headlight.diffuse[:] = [0.7] * 3
    m.vis.headlight.specular[:] = [0.1] * 3
    d = mujoco.MjData(m)
    q = [float(x) for x in a.qpos.split()]
    d.qpos[: len(q)] = q
    mujoco.mj_forward(m, d)
    cam = mujoco.MjvCamera()
    cam.lookat[:] = a.lookat
    cam.distance, cam.azimuth, cam.elevation = a.distance, a.azimuth, a.elevation
    opt = mujoco.MjvOption()
    opt.geomgroup[:] = 1
    r = mujoco.Renderer(m, 700, 900)
    r.update_scene(d, cam, opt)
    img = r.render().copy()
    background = (img == 0).all(axis=2)
    img[background] = 255
    ys, xs = np.where(~background)
    pad = 20
    box = (max(xs.min() - pad, 0), max(ys.min() - pad, 0),
           min(xs.max() + pad, img.shape[1]), min(ys.max() + pad, img.shape[0]))
    Image.fromarray(img).crop(box).save(a.png, optimize=True)


if __name__ == "__main__":
    main()
