"""The operator `bpy.ops.object.bvseg_colliders()`: bvseg on every selected mesh object and
armature, then one collider object per volume.

From a script (EXEC_DEFAULT) it runs to the end, with the window manager's progress; from the
panel or a menu (INVOKE_DEFAULT) it is modal: the runs go on in the background, the status bar
says how far each has got, Esc stops them.
"""

import json
import os
import tempfile
import traceback

import numpy as np
from bpy.types import Operator
from mathutils import Matrix

from . import colliders, export, geometry, naming, props, runner

# Blender holds vertices and transforms in single precision: a coordinate rounds by up to 6e-8
# of its size, and each product of transforms that places a collider in the world by a few
# times that, of the world coordinates. Every collider grows by a millionth of the largest
# coordinate, in the fitting space and in the world, so that the enclosure survives both.
F32_MARGIN = 1e-6


def f32_margin(points, fit_to_world):
    """The margin (fitting-space units) that holds the enclosure through single precision, for
    `points` (n x 3, fitting space) placed in the world by `fit_to_world` (4x4)."""
    m = np.array(fit_to_world, dtype=np.float64)
    world = points @ m[:3, :3].T + m[:3, 3]
    # A fitting-space length maps to at least the smallest singular value times it.
    shrink = max(float(np.linalg.svd(m[:3, :3], compute_uv=False).min()), 1e-12)
    largest = max(float(np.abs(points).max(initial=0.0)), float(np.abs(world).max(initial=0.0)) / shrink)
    return F32_MARGIN * max(largest, 1e-30)


def unexpected(error):
    """The report line of an exception the add-on did not expect; the traceback goes to the
    system console for a bug report."""
    traceback.print_exc()
    return f"unexpected {type(error).__name__} in the bvseg add-on: {error} (traceback on the console)"


def armature_of(obj):
    """The armature object that deforms a mesh object (its first enabled Armature modifier)."""
    for m in obj.modifiers:
        if m.type == "ARMATURE" and m.object is not None and m.object.type == "ARMATURE" and m.show_viewport:
            return m.object
    return None


def preferred_path(context):
    addon = context.preferences.addons.get(__package__)
    return getattr(addon.preferences, "bvseg_path", "") if addon is not None else ""


class Job:
    """One bvseg run: a static mesh, or an armature with the meshes it deforms."""

    def __init__(self, source, meshes=None):
        self.source = source  # the object the colliders hang under
        self.meshes = meshes  # None for a static mesh
        if meshes is None or len(meshes) != 1:
            self.name = source.name
        else:
            self.name = meshes[0].name
        self.run = None
        self.input = None
        self.args = []
        self.placement = None

    def start(self, context, exe, settings, tmp):
        """Exports the input and starts bvseg. Raises ExportError or RunError."""
        if self.meshes is None:
            self.input = os.path.join(tmp, "input.obj")
            depsgraph = context.evaluated_depsgraph_get()
            to_world = self.source.matrix_world.copy()
            if settings.space == "WORLD":
                points = export.write_obj(self.source, depsgraph, self.input, [list(r) for r in to_world])
                fit_to_world = Matrix.Identity(4)
                self.placement = colliders.Placement(self.source, fit_to_world)
            else:
                points = export.write_obj(self.source, depsgraph, self.input)
                fit_to_world = to_world
                self.placement = colliders.Placement(self.source)
        else:
            self.input = os.path.join(tmp, "input.glb")
            points, nodes = export.write_skinned_glb(self.source, self.meshes, self.input)
            bones = {i: n for i, n in enumerate(nodes) if n is not None}
            bones.update({n: n for n in nodes if n is not None})
            fit_to_world = Matrix.Identity(4)
            self.placement = colliders.Placement(self.source, fit_to_world, bones)
        margin = settings.margin + f32_margin(points, fit_to_world)
        self.args = runner.segment_args(settings, margin)
        self.run = runner.Run(exe, self.input, os.path.join(tmp, "volumes.json"), self.args)

    def named(self, message):
        """A message for the report: the temporary file's path replaced by the object's name,
        which leads the line."""
        if self.input:
            message = message.replace(self.input + ": ", "").replace(self.input, self.name)
        return message if message.startswith(self.name + ":") else f"{self.name}: {message}"

    def finish(self, context, settings):
        """Reads the volumes and builds the colliders; returns (report line, warnings)."""
        doc = self.run.result()
        try:
            objects, warnings = colliders.build(context, self.name, self.placement, doc["volumes"], settings)
        except geometry.VolumeError as e:
            raise runner.RunError(f"bvseg's volumes file has a bad volume: {e}") from e
        # How these colliders were made, to run it again: `bvseg segment INPUT ARGS`, INPUT the
        # evaluated mesh in the fitting space (OBJ) or the armature with its meshes (GLB).
        self.source["bvseg_run"] = json.dumps(
            {
                "input": os.path.basename(self.input),
                "space": "WORLD" if self.meshes else settings.space,
                "args": self.args,
            }
        )
        kinds = {}
        for o in objects:
            word = naming.PLAIN_KIND.get(o["bvseg_shape"], o["bvseg_shape"])
            kinds[word] = kinds.get(word, 0) + 1
        line = f"{self.name}: {len(objects)} colliders ({', '.join(f'{n} {k}' for k, n in kinds.items())})"
        metrics = doc.get("metrics", {}) if isinstance(doc.get("metrics"), dict) else {}
        if isinstance(metrics.get("tov"), (int, float)):
            line += f", outside volume {metrics['tov']:.3f}"
        if isinstance(metrics.get("protrusion_rel"), (int, float)):
            line += f", protrusion {metrics['protrusion_rel']:.3f} of the diagonal"
        return line, self.run.warnings + warnings


def plan(objects, per_bone, scene):
    """The jobs for the selected objects, and a line for each object left out."""
    static, rigs, skipped = [], {}, []
    for o in objects:
        if o.type == "MESH":
            arm = armature_of(o) if per_bone else None
            if arm is not None:
                rigs.setdefault(arm, []).append(o)
            elif o not in static:
                static.append(o)
        elif o.type == "ARMATURE":
            if per_bone:
                rigs.setdefault(o, [])
            else:
                static += [
                    m for m in scene.objects if m.type == "MESH" and armature_of(m) is o and m not in static
                ]
        else:
            skipped.append(f"{o.name}: not a mesh or an armature ({o.type.lower()})")
    jobs = [Job(o) for o in static]
    for arm, meshes in rigs.items():
        if not meshes:
            meshes = [m for m in scene.objects if m.type == "MESH" and armature_of(m) is arm]
        if not meshes:
            skipped.append(f"{arm.name}: no mesh is deformed by this armature")
            continue
        jobs.append(Job(arm, meshes))
    return jobs, skipped


class Session:
    """The jobs of one operator call, run one after the other."""

    def __init__(self, context, settings):
        self.settings = settings
        jobs, self.skipped = plan(context.selected_objects, settings.per_bone, context.scene)
        if not jobs:
            raise runner.RunError("; ".join(self.skipped) or "select mesh objects or armatures")
        if settings.target == "custom":
            runner.segment_args(settings, 0.0)  # a missing kinds list, before anything runs
        self.exe = runner.find_bvseg(preferred_path(context))
        self.jobs = jobs
        self.index = -1
        self.done, self.failed, self.warnings = [], [], []
        self._tmp = tempfile.TemporaryDirectory(prefix="bvseg-blender-")

    @property
    def job(self):
        return self.jobs[self.index] if 0 <= self.index < len(self.jobs) else None

    def next(self, context):
        """Starts the next job that starts; returns False when none is left."""
        while self.index + 1 < len(self.jobs):
            self.index += 1
            job = self.jobs[self.index]
            for name in os.listdir(self._tmp.name):
                os.remove(os.path.join(self._tmp.name, name))
            try:
                job.start(context, self.exe, self.settings, self._tmp.name)
                return True
            except (export.ExportError, runner.RunError) as e:
                self.failed.append(job.named(str(e)))
            except Exception as e:  # a bug: reported, with the traceback on the console
                self.failed.append(job.named(unexpected(e)))
        return False

    def finish_job(self, context):
        job = self.job
        try:
            line, warnings = job.finish(context, self.settings)
            self.done.append(line)
            self.warnings += [job.named(w) for w in warnings]
        except runner.RunError as e:
            self.failed.append(job.named(str(e)))
        except ReferenceError:
            self.failed.append(f"{job.name}: the object was deleted during the run")
        except Exception as e:  # a bug: reported, with the traceback on the console
            self.failed.append(job.named(unexpected(e)))

    def status(self):
        job = self.job
        if job is None or job.run is None:
            return "bvseg"
        run = job.run
        text = f"bvseg {self.index + 1}/{len(self.jobs)}: {job.name}"
        if run.k:
            text += f": {run.k} parts"
        if run.tov is not None:
            text += f", outside volume {run.tov:.3f} (aim {self.settings.tov:g})"
        return text

    def progress(self):
        """Jobs done plus the current one's parts against its budget, 0 .. len(jobs)."""
        job = self.job
        if job is None or job.run is None:
            return max(self.index, 0)
        budget = self.settings.k or self.settings.max_k
        return self.index + min(0.95, job.run.k / max(budget, 1))

    def cancel(self):
        job = self.job
        if job is not None and job.run is not None:
            job.run.cancel()

    def close(self):
        self._tmp.cleanup()

    def report(self, op):
        """Reports the outcome to Blender; returns the operator's result."""
        for line in self.skipped:
            op.report({"WARNING"}, line)
        for line in self.warnings:
            op.report({"WARNING"}, line)
        # A failure is an error when nothing was made; beside colliders that were, a warning (an
        # error would make a script's call raise although the scene changed).
        for line in self.failed:
            op.report({"WARNING"} if self.done else {"ERROR"}, line)
        for line in self.done:
            op.report({"INFO"}, line)
        return {"FINISHED"} if self.done else {"CANCELLED"}


class BVSEG_OT_colliders(Operator):
    """Wrap the selected meshes in tight colliders with bvseg, named for the chosen engine"""

    bl_idname = "object.bvseg_colliders"
    bl_label = "Make Colliders"
    bl_options = {"REGISTER", "UNDO"}
    __annotations__ = props.settings_properties()

    _session = None
    _timer = None

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def execute(self, context):
        try:
            session = Session(context, self)
        except runner.RunError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, len(session.jobs))
        try:
            while session.next(context):
                print(f"bvseg: {session.job.name} ({session.index + 1}/{len(session.jobs)})")
                session.job.run.wait(lambda run: wm.progress_update(session.progress()))
                session.finish_job(context)
        finally:
            session.cancel()
            session.close()
            wm.progress_end()
        return session.report(self)

    def invoke(self, context, event):
        try:
            session = Session(context, self)
        except runner.RunError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if not session.next(context):
            session.close()
            return session.report(self)
        self._session = session
        wm = context.window_manager
        wm.progress_begin(0, len(session.jobs))
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context):
        text = self._session.status() + " · Esc to stop"
        if context.workspace is not None:
            context.workspace.status_text_set(text)
        context.window_manager.progress_update(self._session.progress())

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        self._session.close()

    def modal(self, context, event):
        session = self._session
        if event.type == "ESC" and event.value == "PRESS":
            session.cancel()
            self._end(context)
            done = len(session.done)
            self.report(
                {"WARNING"}, f"bvseg stopped by Esc; {done} object{'s' if done != 1 else ''} got colliders"
            )
            for line in session.done:
                self.report({"INFO"}, line)
            return {"FINISHED"} if done else {"CANCELLED"}
        if event.type != "TIMER" or event.timer is not self._timer:
            return {"PASS_THROUGH"}
        if not session.job.run.poll():
            self._status(context)
            return {"RUNNING_MODAL"}
        session.finish_job(context)
        if session.next(context):
            self._status(context)
            return {"RUNNING_MODAL"}
        self._end(context)
        return session.report(self)


def menu_entry(self, context):
    self.layout.operator(BVSEG_OT_colliders.bl_idname, text="Colliders (bvseg)")
