#!/usr/bin/env bash
# Writes the HTML report page of every shipped scenario, with every kind of analysis page
# (run; sensitivity, allocation, stack and sweep where the scenario is made for them), into
# OUT_DIR/html: what scripts/report-screenshots.sh photographs and
# scripts/check-page-print.py prints.
#
#   scripts/report-pages.sh [OUT_DIR]      (default: target/report-pages)
#
# Sample counts are kept small so that the whole script runs in a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/report-pages}"
mkdir -p "$out/html"
out="$(cd "$out" && pwd)"
cargo build --release --locked -p rvtol --quiet
rvtol=target/release/rvtol
for scenario in scenarios/*.json; do
  name="$(basename "$scenario" .json)"
  dir="$out/html"
  json="$dir/$name.run.json"
  case "$name" in
    rv40e-transmission*) samples=2000 ;;
    *torsion*|rv40e-elastic|rv80e-contact) samples=20000 ;;
    *) samples=100000 ;;
  esac
  # A run that ends with exit 1 (a requirement missed) still writes its report.
  "$rvtol" run "$scenario" --samples "$samples" --json "$json" --quiet > "$dir/$name.run.txt" || [ $? -eq 1 ]
  reports=("$json")
  case "$name" in
    rv20e-hysteresis|ishigami|sobol-g|linear-stack-correlated|allocation-linear)
      "$rvtol" sensitivity "$scenario" --samples 4096 --bootstrap 200 --json "$dir/$name.sensitivity.json" --quiet > /dev/null
      reports+=("$dir/$name.sensitivity.json") ;;
    shapley-linear-gaussian)
      "$rvtol" sensitivity "$scenario" --samples 4096 --bootstrap 200 --shapley --json "$dir/$name.sensitivity.json" --quiet > /dev/null
      reports+=("$dir/$name.sensitivity.json") ;;
  esac
  case "$name" in
    allocation-linear)
      "$rvtol" allocate "$scenario" --output gap_mm --target "sd <= 0.02" --json "$dir/$name.allocation.json" --quiet > /dev/null || [ $? -eq 1 ]
      reports+=("$dir/$name.allocation.json") ;;
    rv20e-selective-fitting)
      "$rvtol" allocate "$scenario" --output hysteresis_arcmin --target "p99.865 <= 1.0" --json "$dir/$name.allocation.json" --quiet > /dev/null || [ $? -eq 1 ]
      reports+=("$dir/$name.allocation.json") ;;
  esac
  case "$name" in
    rv20e-hysteresis|linear-stack-correlated|motor-assembly-stack|pin-in-hole)
      "$rvtol" stack "$scenario" --samples 20000 --json "$dir/$name.stack.json" --quiet > /dev/null
      reports+=("$dir/$name.stack.json") ;;
  esac
  case "$name" in
    rv20e-hysteresis)
      "$rvtol" sweep "$scenario" --set reducer.params.shift_modification_mm=-0.016:-0.008:5 --set reducer.params.equidistant_modification_mm=-0.012,-0.010,-0.008 --output hysteresis_arcmin --samples 20000 --json "$dir/$name.sweep.json" --quiet > /dev/null
      reports+=("$dir/$name.sweep.json") ;;
    pin-in-hole)
      "$rvtol" sweep "$scenario" --set "models[0].params.hole_oversize_mm=0:0.004:5" --samples 20000 --json "$dir/$name.sweep.json" --quiet > /dev/null
      reports+=("$dir/$name.sweep.json") ;;
  esac
  "$rvtol" report "${reports[@]}" --scenario "$scenario" -o "$dir/$name.html" > /dev/null
done
echo "pages in $out/html"
