# Shared by the bench scripts (source it after setting ROOT and NAME):
# locates Radiance as tests/common/mod.rs does (TESSERA_RADIANCE_BIN, PATH, pyradiance),
# exports PATH and RAYPATH, builds tpict unless NO_BUILD or TPICT is set, and sets TPICT.

find_radiance() {
    if [[ -n "${TESSERA_RADIANCE_BIN:-}" && -x "$TESSERA_RADIANCE_BIN/rpict" ]]; then
        echo "$TESSERA_RADIANCE_BIN"
        return
    fi
    local p
    if p=$(command -v rpict 2>/dev/null); then
        dirname "$p"
        return
    fi
    p=/opt/radvenv/lib/python3.11/site-packages/pyradiance/bin
    if [[ -x "$p/rpict" ]]; then
        echo "$p"
        return
    fi
    return 1
}
RADBIN=$(find_radiance) || {
    echo "$NAME: Radiance not found (set TESSERA_RADIANCE_BIN to the folder holding rpict)" >&2
    exit 1
}
export PATH="$RADBIN:$PATH"
export RAYPATH=".:$(dirname "$RADBIN")/lib"

if [[ -z "${NO_BUILD:-}" && -z "${TPICT:-}" ]]; then
    echo "$NAME: cargo build --release" >&2
    (cd "$ROOT" && cargo build --release --quiet --bin tpict)
fi
TPICT=${TPICT:-"$ROOT/target/release/tpict"}
[[ $TPICT == /* ]] || TPICT="$PWD/$TPICT"
[[ -x "$TPICT" ]] || { echo "$NAME: $TPICT missing" >&2; exit 1; }

# work_dir: a private work directory in $TMP, removed when the script exits (an
# interrupt exits with 130).
work_dir() {
    TMP=$(mktemp -d "${TMPDIR:-/tmp}/tessera-$NAME.XXXXXX")
    trap 'rm -rf "$TMP"' EXIT
    trap 'exit 130' INT TERM
}

# bright PIC OUT: reduce PIC to $RED x $RED pixels and write one brightness per pixel.
bright() {
    pfilt -1 -r 1 -x "$RED" -y "$RED" "$1" | pvalue -h -H -o -b -d >"$2"
}

# relrms TEST REF: relative RMS error of two brightness files; reference values below
# $FLOOR times their mean count as that floor.
relrms() {
    paste "$1" "$2" | awk -v f="$FLOOR" '
        { t[NR] = $1; r[NR] = $2; s += $2 }
        END {
            fl = f * s / NR
            for (i = 1; i <= NR; i++) { d = r[i] > fl ? r[i] : fl; e += ((t[i] - r[i]) / d) ^ 2 }
            printf "%.5f\n", sqrt(e / NR)
        }'
}

# The direct-light benchmark scenes (bench/run.sh, bench/direct_error.sh):
# scene_def NAME prints "folder (under tests/scenes) | files | view file | -av".
scene_def() {
    case $1 in
    spheres | curved | glassy | mirrors | aniso) echo "|$1.rad|$1.vf|.05" ;;
    examp) echo "examp|examp|examp.vp|.5" ;;
    daffodil) echo "daffodil|daffodil.flat.rad room.flat.rad|daffodil.vp|.2" ;;
    *) return 1 ;;
    esac
}
