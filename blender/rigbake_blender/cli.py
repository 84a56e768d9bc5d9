# Runs the rigbake CLI for the panel's operators. rigbake prints a user error as one line,
# "CODE path: what is wrong" (docs/errors.md), which becomes the Blender report as it is.
import os
import shutil
import subprocess

import bpy


def executable(context):
    prefs = context.preferences.addons.get(__package__)
    path = prefs.preferences.rigbake_path if prefs is not None else ""
    return path or os.environ.get("RIGBAKE") or shutil.which("rigbake") or "rigbake"


def run(context, arguments):
    """(True, summary) or (False, the one-line error)."""
    command = [executable(context)] + [str(a) for a in arguments]
    try:
        done = subprocess.run(command, capture_output=True, text=True)
    except OSError as error:
        return False, "BLENDER_RIGBAKE_NOT_FOUND %s: %s (set the path in the add-on's preferences)" % (command[0], error.strerror)
    lines = [line for line in (done.stderr + "\n" + done.stdout).splitlines() if line.strip()]
    if done.returncode != 0:
        errors = [line for line in done.stderr.splitlines() if line.strip()]
        return False, (errors[-1] if errors else "rigbake exited with status %d" % done.returncode)
    return True, (lines[-1] if lines else "done")
