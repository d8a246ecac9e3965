"""Running the bvseg command line: finding it, its arguments, its progress, its result.

No bpy here: a Run is a subprocess whose stderr a thread reads line by line, so that Blender's
main thread only polls (a modal operator's timer, or a loop in a script's synchronous call).
"""

import json
import os
import queue
import re
import shutil
import subprocess
import threading

# `[split    ] k=23  F=1.075  TOV=0.356  MOV=1.229  protrusion=0.153` on stderr, one per step.
_STEP = re.compile(r"^\[(\w+)\s*\]\s+k=(\d+)\s.*?TOV=([0-9.eE+-]+)")


class RunError(Exception):
    """A run that could not start, failed, or wrote no usable file: one line for the user."""


def find_bvseg(preferred=""):
    """The bvseg executable: `preferred` (the add-on preference) when set, else `bvseg` on PATH.
    Raises RunError saying where it looked."""
    if preferred:
        path = os.path.abspath(os.path.expanduser(preferred))
        if os.path.isdir(path):
            path = os.path.join(path, "bvseg.exe" if os.name == "nt" else "bvseg")
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path
        raise RunError(f"bvseg not found at {preferred} (the add-on's preference)")
    found = shutil.which("bvseg")
    if found:
        return found
    raise RunError(
        "bvseg not found: set its path in the add-on's preferences, or put it on PATH "
        "(cargo install --path crates/bvseg-cli)"
    )


def segment_args(settings, margin):
    """The `bvseg segment` options of the settings (an object with the operator's properties)
    and `margin` (mesh units, already including the float32 allowance)."""
    args = []
    target = settings.target
    if target == "custom":
        kinds = settings.kinds.replace(" ", "")
        if not kinds:
            raise RunError("target 'custom' needs a list of kinds (e.g. obb,sphere,capsule)")
        args += ["--bv", kinds]
    elif target != "primitives":
        args += ["--target", target]
    if settings.k > 0:
        args += ["--k", str(settings.k)]
    # Blender keeps float properties in single precision: 7 digits give back what was typed.
    args += ["--tov", f"{settings.tov:.7g}"]
    args += ["--max-protrusion", f"{settings.max_protrusion:.7g}"]
    args += ["--max-k", str(settings.max_k)]
    args += ["--samples", str(settings.samples)]
    args += ["--max-hull-vertices", str(settings.max_hull_vertices)]
    args += ["--margin", repr(float(margin))]
    return args


class Run:
    """One `bvseg segment INPUT ... -o OUTPUT` process."""

    def __init__(self, exe, input_path, output_path, args):
        self.output_path = output_path
        # The hierarchy is not used here, and costs about a sixth of a run.
        self.command = [exe, "segment", input_path, *args, "-o", output_path, "--no-hierarchy"]
        self.lines = queue.Queue()
        self.errors = []  # `bvseg: error: ...` lines
        self.warnings = []  # `bvseg: warning: ...` lines
        self.k = 0
        self.tov = None
        try:
            self.process = subprocess.Popen(
                self.command,
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,  # the summary: the report takes it from the file
                stderr=subprocess.PIPE,
                text=True,
                errors="replace",
            )
        except OSError as e:
            raise RunError(f"cannot run {exe}: {e.strerror or e}") from e
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.process.stderr:
            self.lines.put(line.rstrip("\n"))
        self.process.stderr.close()

    def poll(self):
        """Takes in the stderr lines read so far; returns True once the process has ended and
        every line is in."""
        while True:
            try:
                line = self.lines.get_nowait()
            except queue.Empty:
                break
            self._take(line)
        if self.process.poll() is None:
            return False
        self._reader.join()
        while not self.lines.empty():
            self._take(self.lines.get_nowait())
        return True

    def _take(self, line):
        m = _STEP.match(line)
        if m:
            self.k = int(m.group(2))
            try:
                self.tov = float(m.group(3))
            except ValueError:
                pass
        elif line.startswith("bvseg: error:"):
            self.errors.append(line[len("bvseg: error:") :].strip())
        elif line.startswith("bvseg: warning:"):
            self.warnings.append(line[len("bvseg: warning:") :].strip())
        elif line.strip() and not line.startswith("["):
            self.warnings.append(line.strip())

    def wait(self, on_progress=None, interval=0.1):
        """Blocks until the process ends, calling on_progress(run) whenever a step came in."""
        last = None
        while True:
            done = self.poll()
            if on_progress is not None and (self.k, self.tov) != last:
                last = (self.k, self.tov)
                on_progress(self)
            if done:
                return
            try:
                line = self.lines.get(timeout=interval)
            except queue.Empty:
                continue
            self._take(line)

    def cancel(self):
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()
        self._reader.join()

    def result(self):
        """The volumes document, once ended. Raises RunError."""
        code = self.process.returncode
        if code not in (0, None):
            detail = self.errors[0] if self.errors else f"exit status {code}"
            raise RunError(f"bvseg failed: {detail}")
        try:
            with open(self.output_path, encoding="utf-8") as f:
                doc = json.load(f)
        except OSError as e:
            raise RunError(f"bvseg wrote no volumes file: {e.strerror or e}") from e
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise RunError(f"bvseg's volumes file is not JSON: {e}") from e
        if not isinstance(doc, dict) or not str(doc.get("schema", "")).startswith("bvseg.volumes/"):
            raise RunError("bvseg's output is not a bvseg.volumes document")
        volumes = doc.get("volumes")
        if not isinstance(volumes, list) or not volumes:
            raise RunError("bvseg's volumes file has no volumes")
        return doc
