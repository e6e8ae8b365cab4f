#!/usr/bin/env bash
# `make blender-test`: our GLB in Blender's glTF importer, and the add-on end to end.
# Needs Debian's blender and python3-numpy (the Makefile target installs them as root).
# BPY_PYTHON=/path/to/python (a Python with PyPI's `bpy` module, e.g. bpy 5.0.1) runs the
# same checks in that Blender instead (Sapling is not bundled there: those are skipped).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${BPY_PYTHON:-}" ]; then
    command -v blender >/dev/null || { echo "blender-test: blender is not installed" >&2; exit 2; }
    RUN=(blender -b --factory-startup --python-exit-code 1 --python)
else
    RUN=("$BPY_PYTHON")
fi
# this checkout's code first, whichever checkout the venv was installed from
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
start=$(date +%s)
.venv/bin/treesketch grow --species maple --seed 3 --out "$T/maple.glb" --save-params "$T/maple.json" \
    --preset "$T/maple_sapling.py"
.venv/bin/treesketch grow --species maple --seed 3 --out "$T/maple.obj"
HEIGHT=$(.venv/bin/python -c "import sys; from weberpenn import grow, build_mesh, load_params
print(build_mesh(grow(load_params(sys.argv[1]))).bounds()[1, 2])" "$T/maple.json")
.venv/bin/python scripts/blender_addon_zip.py "$T/treesketch_addon.zip"
# a private user-scripts folder: installing the add-on leaves the user's Blender alone
set +e
BLENDER_USER_SCRIPTS="$T/scripts" BLENDER_USER_CONFIG="$T/config" \
    "${RUN[@]}" scripts/blender_test.py -- \
    "$T/treesketch_addon.zip" "$T/maple.glb" "$HEIGHT" "$PWD/.venv/bin/treesketch" \
    > "$T/blender.log" 2>&1
rc=$?
set -e
grep -E "BLENDER_TEST|Error|Traceback|assert|treesketch: (error|warning)" "$T/blender.log" || true
[ "$rc" = 0 ] || tail -30 "$T/blender.log"
echo "blender-test: exit $rc in $(( $(date +%s) - start )) s"
exit "$rc"
