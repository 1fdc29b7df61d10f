#!/usr/bin/env bash
# A package, not a checkout (issue 36, part 7): build the wheel, install it into a fresh
# venv outside the repository, and from there run `mresim warmup` and the quickstart (which
# must then compile no kernel), validate every shipped
# scenario and check the package data (maps the package draws, the viewer's assets) are in
# it. Run by .ci/run; by hand: tools/check_wheel.sh (about 4 minutes).
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
python3 -m pip wheel --no-deps -q -w "$work/dist" "$repo"
python3 -m venv "$work/venv"
"$work/venv/bin/pip" install -q --upgrade pip
"$work/venv/bin/pip" install -q "$work"/dist/mresim_phys-*.whl
cd "$work"  # nothing of the checkout on the path
"$work/venv/bin/python" - <<'PY'
import importlib.resources as res
import mresim_phys
assert "site-packages" in mresim_phys.__file__, mresim_phys.__file__
static = res.files("mresim_phys.viewer") / "static"
names = sorted(p.name for p in static.iterdir())
assert any(n.endswith(".html") for n in names) and any(n.endswith(".js") for n in names), names
data = [p.name for p in (res.files("mresim_phys") / "data").iterdir() if p.name.endswith(".png")]
assert data, "mresim_phys/data/*.png missing from the wheel"
print(f"wheel: {mresim_phys.__file__}; viewer assets {names}; data {sorted(data)}")
PY
# the README's first command: compile the kernels once, then the quickstart compiles none
"$work/venv/bin/mresim" warmup
started=$(date +%s.%N)
NUMBA_DEBUG_CACHE=1 "$work/venv/bin/mresim" run "$repo/scenarios/01_quickstart.yaml" \
    --out "$work/run" --quiet > "$work/quickstart.log"
seconds=$(python3 -c "print(round($(date +%s.%N) - $started, 1))")
test -s "$work/run/metrics.csv" && test -s "$work/run/final.png"
if grep -q "data saved" "$work/quickstart.log"; then
    echo "wheel: the quickstart compiled kernels that mresim warmup had not:" >&2
    grep "data saved" "$work/quickstart.log" >&2
    exit 1
fi
echo "wheel: after mresim warmup the quickstart compiled no kernel and took $seconds s"
for scenario in "$repo"/scenarios/*.yaml; do
    "$work/venv/bin/mresim" validate "$scenario" > /dev/null
done
echo "wheel: quickstart ran, $(ls "$repo"/scenarios/*.yaml | wc -l) scenarios validated"
