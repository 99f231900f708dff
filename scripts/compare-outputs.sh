#!/usr/bin/env bash
# Writes what one rvtol binary makes of every shipped scenario into a folder, so that two
# builds can be compared byte for byte (`diff -r`): a refactoring that claims to change no
# behaviour runs this with the binary before and after it.
#
#   scripts/compare-outputs.sh BINARY OUT_DIR [SCENARIO_DIR]
#   diff -r OUT_DIR_BEFORE OUT_DIR_AFTER
#
# Per scenario: `run` (JSON, text and HTML page; Monte Carlo with exact percentiles, with a
# quantile sketch, with an rqmc design), `nominal`, `sensitivity` (Monte Carlo; Shapley
# effects where the scenario has no Eq. 11 constraint and few sources), `baseline` and
# `check` against it (exact, from a sketch, and of the scenario drawn by an rqmc design), a
# run and an analysis in two shards merged; per scenario with an `allocation` section,
# `allocate`; besides, one `evaluate` of sampled rows, one `fit`, and `validate` of a few
# thousand mutated scenarios. Every command's reports, its text on standard output, its
# error line and its exit code are kept (shard files are not: they carry the build's
# hash). Sample counts are small: the sweep takes about five minutes on two cores; set
# RVTOL_COMPARE_SCALE=k to multiply them.
set -u
binary=$(realpath "$1")
out=$2
scenarios=$(realpath "${3:-$(dirname "$0")/../scenarios}")
scale=${RVTOL_COMPARE_SCALE:-1}
mkdir -p "$out"
out=$(realpath "$out")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Paths in messages are written as OUT and WORK at the end, so two sweeps compare.

# Runs one command, keeping its standard output, standard error and exit code under
# $out/NAME.{stdout,stderr,code}.
record() {
    local name=$1
    shift
    (cd "$work" && RVTOL_ESTIMATE_THRESHOLD_SECONDS=1e9 "$binary" "$@" --quiet \
        >"$out/$name.stdout" 2>"$out/$name.stderr")
    echo $? >"$out/$name.code"
}

# Like `record`, for the commands without --quiet.
record_plain() {
    local name=$1
    shift
    (cd "$work" && "$binary" "$@" >"$out/$name.stdout" 2>"$out/$name.stderr")
    echo $? >"$out/$name.code"
}

# Scenarios written to the work folder (an rqmc variant, mutants) find the shared files
# they name (reducers/) beside them.
for shared in "$scenarios"/*/; do
    [ -d "$shared" ] && cp -r "$shared" "$work/"
done

n_run=$((20000 * scale))
n_sens=$((2048 * scale))
for path in "$scenarios"/*.json; do
    s=$(basename "$path" .json)
    echo "$s" >&2
    record "$s.run" run "$path" --samples "$n_run" --seed 7 --json "$out/$s.run.json" \
        --html "$out/$s.run.html"
    record "$s.run-sketch" run "$path" --samples "$n_run" --seed 7 \
        --exact-percentile-limit 100 --json "$out/$s.run-sketch.json"
    record "$s.run-rqmc" run "$path" --samples $((8 * 512 * scale)) --seed 7 \
        --sampling rqmc --replicates 8 --json "$out/$s.run-rqmc.json"
    record_plain "$s.nominal" nominal "$path" --json "$out/$s.nominal.json"
    record "$s.sensitivity" sensitivity "$path" --samples "$n_sens" --seed 7 \
        --bootstrap 40 --json "$out/$s.sensitivity.json" --html "$out/$s.sensitivity.html"
    case $s in
    shapley-linear-gaussian | allocation-linear | ishigami | sobol-g | linear-stack-correlated)
        record "$s.shapley" sensitivity "$path" --samples "$n_sens" --seed 7 --bootstrap 40 \
            --shapley --permutations 60 --outer 32 --json "$out/$s.shapley.json"
        ;;
    esac
    record "$s.baseline" baseline "$path" --samples "$n_run" --seed 7 -o "$out/$s.baseline.json"
    record "$s.check" check "$path" --baseline "$out/$s.baseline.json" --seed 8 \
        --json "$out/$s.check.json" --junit "$out/$s.check.xml"
    record "$s.check-one-sided" check "$path" --baseline "$out/$s.baseline.json" --seed 9 \
        --one-sided --json "$out/$s.check-one-sided.json"
    record "$s.baseline-sketch" baseline "$path" --samples "$n_run" --seed 7 \
        --exact-percentile-limit 100 -o "$out/$s.baseline-sketch.json"
    record "$s.check-sketch" check "$path" --baseline "$out/$s.baseline-sketch.json" --seed 8 \
        --json "$out/$s.check-sketch.json"
    # The scenario drawn by an rqmc design (the gate's replicate bands).
    python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
d.update(sampling="rqmc", replicates=8, samples=int(sys.argv[3]))
json.dump(d, open(sys.argv[2], "w"))' "$path" "$work/$s.rqmc.json" $((8 * 1024 * scale))
    record "$s.baseline-rqmc" baseline "$work/$s.rqmc.json" -o "$out/$s.baseline-rqmc.json"
    record "$s.check-rqmc" check "$work/$s.rqmc.json" --baseline "$out/$s.baseline-rqmc.json" \
        --seed 8 --require "p50 <= 1e9" --json "$out/$s.check-rqmc.json"
    for k in 0 1; do
        record "$s.shard$k" run "$path" --samples "$n_run" --seed 7 --shard $k/2 \
            --partial "$work/$s.$k.shard"
        record "$s.sensitivity-shard$k" sensitivity "$path" --samples "$n_sens" --seed 7 \
            --bootstrap 40 --shard $k/2 --partial "$work/$s.sensitivity.$k.shard"
    done
    record "$s.merge" merge "$work/$s.0.shard" "$work/$s.1.shard" --json "$out/$s.merge.json"
    record "$s.merge-check" merge "$work/$s.0.shard" "$work/$s.1.shard" \
        --check "$out/$s.baseline.json" --json "$out/$s.merge-check.json"
    record "$s.merge-baseline" merge "$work/$s.0.shard" "$work/$s.1.shard" \
        --baseline "$out/$s.merge-baseline.json"
    record "$s.merge-sensitivity" merge "$work/$s.sensitivity.0.shard" \
        "$work/$s.sensitivity.1.shard" --json "$out/$s.merge-sensitivity.json"
    rm -f "$work"/*.shard
done

alloc() {
    local name=$1 scenario=$2 output=$3 target=$4 samples=$5
    record "$name" allocate "$scenarios/$scenario.json" --output "$output" --target "$target" \
        --samples "$samples" --json "$out/$name.json" --html "$out/$name.html"
}
alloc allocation-linear.allocate allocation-linear gap_mm "sd <= 0.02" $((20000 * scale))
alloc allocation-linear.allocate-ppm allocation-linear gap_mm "ppm_out <= 2000" $((20000 * scale))
alloc rv20e-selective-fitting.allocate rv20e-selective-fitting hysteresis_arcmin "p99.865 <= 1.0" $((8000 * scale))
alloc rv20e-hysteresis.allocate rv20e-hysteresis hysteresis_arcmin "cpk >= 1.33" $((4000 * scale))

# evaluate: the rows of a small run, evaluated again; fit: a normal model of the sampled
# inputs of a part.
record samples run "$scenarios/linear-stack-correlated.json" --samples 200 --seed 3 \
    --samples-out "$out/samples.csv" --json "$out/samples.run.json"
record evaluate evaluate "$scenarios/linear-stack-correlated.json" --inputs "$out/samples.csv" \
    -o "$out/evaluate.csv"
record samples-rv20e run "$scenarios/rv20e-hysteresis.json" --samples 300 --seed 3 \
    --samples-out "$out/samples-rv20e.csv"
first_part=$(head -1 "$out/samples-rv20e.csv" | tr ',' '\n' | grep '\.du' | head -1 | sed 's/\.du.*//')
record_plain fit fit "$out/samples-rv20e.csv" --part "$first_part" -o "$out/fit.json"
record_plain fit-all fit "$out/samples.csv"
record_plain fit-variables fit "$out/samples-rv20e.csv" --part nothing
record_plain validate validate "$scenarios/rv20e-lost-motion.json"
record_plain models models
record_plain init init geometric_hysteresis -o "$out/init.json"

# validate of mutated scenarios: every problem each reports, in order (the scenario
# compiler's messages and their order). Deterministic: each scalar and each key of every
# shipped scenario changed in a few ways.
mkdir -p "$work/mutants"
for shared in "$scenarios"/*/; do
    [ -d "$shared" ] && cp -r "$shared" "$work/mutants/"
done
python3 - "$scenarios" "$work/mutants" <<'PY'
import copy, json, os, sys
source, target = sys.argv[1], sys.argv[2]
def places(node, path=()):
    yield path, node
    if isinstance(node, dict):
        for key, value in node.items():
            yield from places(value, path + (key,))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from places(value, path + (index,))
def put(document, path, value):
    node = document
    for step in path[:-1]:
        node = node[step]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
count = 0
for name in sorted(os.listdir(source)):
    if not name.endswith(".json"):
        continue
    document = json.load(open(os.path.join(source, name)))
    for k, (path, node) in enumerate(places(document)):
        if not path or k % 3:
            continue
        changes = [KeyError, "text", -1.5, 0, None, [1, 2]]
        if isinstance(node, (int, float)) and not isinstance(node, bool):
            changes += [node * 1e9, -node]
        for j, value in enumerate(changes):
            if value is KeyError and isinstance(path[-1], int):
                continue
            mutant = copy.deepcopy(document)
            put(mutant, path, value)
            count += 1
            with open(os.path.join(target, "%s.%04d.%d.json" % (name[:-5], k, j)), "w") as f:
                json.dump(mutant, f)
PY
for mutant in "$work"/mutants/*.json; do
    echo "== $(basename "$mutant"): $("$binary" validate "$mutant" 2>&1 >/dev/null | sed "s#$work#WORK#g"; echo "exit ${PIPESTATUS[0]}")"
done >"$out/validate-mutants.txt" 2>&1

for f in "$out"/*; do
    case $f in *.stdout | *.stderr | *.json | *.xml | *.html) sed -i -e "s#$work#WORK#g" -e "s#$out#OUT#g" \
        -e "s#$scenarios#SCENARIOS#g" "$f" ;; esac
done
exit 0
