# Shared by scripts/test and scripts/demo: install what is missing, configure, build.
# Sourced, not executed.

WEFT_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
WEFT_JOBS="${WEFT_JOBS:-$(nproc)}"
# Debian's interpreter: the one python3-numpy and python3-pytest install into
# (a python3 earlier on PATH, e.g. from pyenv, would not see them).
WEFT_PYTHON="${WEFT_PYTHON:-/usr/bin/python3}"

# Debian packages weft builds with (dependencies come only from apt).
WEFT_PACKAGES=(
    cmake g++ make pkg-config
    libembree-dev libtbb-dev libopenexr-dev libstb-dev nlohmann-json3-dev libcli11-dev
    libgtest-dev libgmock-dev libbenchmark-dev pybind11-dev libeigen3-dev libhwy-dev
    libcpp-httplib-dev libpugixml-dev
    python3-dev python3-numpy python3-pytest python3-pil
)

weft_install_deps() {
    local missing=()
    for pkg in "${WEFT_PACKAGES[@]}"; do
        if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
            missing+=("$pkg")
        fi
    done
    if [ ${#missing[@]} -eq 0 ]; then
        return 0
    fi
    echo "weft: installing missing packages: ${missing[*]}"
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null; then sudo="sudo"; else
            echo "weft: need root (or sudo) to install: ${missing[*]}" >&2
            return 1
        fi
    fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# What the browser test of weft view needs (tests/browser/, docs/view.md):
# Debian's chromium, Node.js with npm, and playwright-core from the npm
# registry at the version of tests/browser/package-lock.json. Without them
# the test is skipped, not failed: a warning says so.
weft_install_browser_deps() {
    local missing=()
    [ -x /usr/bin/chromium ] || missing+=(chromium)
    command -v node >/dev/null || missing+=(nodejs)
    command -v npm >/dev/null || missing+=(npm)
    if [ ${#missing[@]} -gt 0 ]; then
        local saved=("${WEFT_PACKAGES[@]}")
        WEFT_PACKAGES=("${missing[@]}")
        weft_install_deps ||
            echo "weft: warning: could not install ${missing[*]}: the browser test will be skipped" >&2
        WEFT_PACKAGES=("${saved[@]}")
    fi
    if command -v npm >/dev/null && [ ! -d "$WEFT_ROOT/tests/browser/node_modules/playwright-core" ]; then
        (cd "$WEFT_ROOT/tests/browser" && npm ci --no-audit --no-fund --loglevel=error) ||
            echo "weft: warning: npm ci in tests/browser failed: the browser test will be skipped" >&2
    fi
}

# Debian's Blender, for the add-on's test (blender/, docs/blender.md) and
# scripts/blender-addon. Without it the test is skipped, not failed.
weft_install_blender() {
    command -v blender >/dev/null && return 0
    local saved=("${WEFT_PACKAGES[@]}")
    WEFT_PACKAGES=(blender)
    weft_install_deps ||
        echo "weft: warning: could not install blender: the Blender add-on test will be skipped" >&2
    WEFT_PACKAGES=("${saved[@]}")
}

# weft_build DIR [cmake args...]: configure and build one build tree, every
# target (library, weft, tests, benches, Python module) unless WEFT_TARGET
# names the one to build (scripts/demo builds only `weft`).
weft_build() {
    local dir="$1"
    shift
    # The Python module is built for Debian's interpreter (docs/python.md).
    cmake -S "$WEFT_ROOT" -B "$dir" -DPython3_EXECUTABLE="$WEFT_PYTHON" "$@" >/dev/null
    if [ -n "${WEFT_TARGET:-}" ]; then
        cmake --build "$dir" -j"$WEFT_JOBS" --target "$WEFT_TARGET"
    else
        cmake --build "$dir" -j"$WEFT_JOBS"
    fi
}
