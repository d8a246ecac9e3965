#!/usr/bin/env bash
# Run the criterion benches (benches/pipeline.rs) and print their medians as a compact
# Markdown table, with the project's speed bars, for BENCHMARKS.md.
#
# Usage: scripts/bench_scaling.sh [--no-run] [--skip-1m] [FILTER]
#   --no-run   only print the table from the last results in target/criterion
#   --skip-1m  leave out scaling_n/1M (the slowest case; sets BVSEG_BENCH_SKIP_1M=1)
#   FILTER     criterion filter (regex on the bench id), e.g. 'assign/|optimize/'
# The full criterion output goes to the terminal and to target/bench_pipeline.log.
# Results older than this run (not re-measured because of a filter) are marked "(old)".
set -euo pipefail

cd "$(dirname "$0")/.."
run=1
filter=""
while [ $# -gt 0 ]; do
    case "$1" in
        --no-run) run=0 ;;
        --skip-1m) export BVSEG_BENCH_SKIP_1M=1 ;;
        -h|--help) sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        -*) echo "unknown option $1" >&2; exit 2 ;;
        *) filter="$1" ;;
    esac
    shift
done

target="${CARGO_TARGET_DIR:-target}"
crit="$target/criterion"
log="$target/bench_pipeline.log"
start_stamp=0
elapsed=""

if [ "$run" = 1 ]; then
    mkdir -p "$target"
    load=$(cut -d' ' -f1 /proc/loadavg 2>/dev/null || echo 0)
    if awk -v l="$load" 'BEGIN { exit !(l > 0.5) }'; then
        echo "note: load average is $load before starting; timings (the thread speedup above all) will be noisy" >&2
    fi
    start_stamp=$(date +%s)
    # shellcheck disable=SC2086
    cargo bench --bench pipeline -- ${filter:+"$filter"} 2>&1 | tee "$log"
    elapsed=$(( $(date +%s) - start_stamp ))
fi

# Median (ns) of one bench id, or nothing when it has no result.
median_ns() {
    local f="$crit/$1/new/estimates.json"
    [ -f "$f" ] || return 0
    sed -E 's/.*"median":\{"confidence_interval":\{[^}]*\},"point_estimate":([-0-9.eE+]+).*/\1/' "$f"
}

# Whether the result of one bench id predates this run.
is_old() {
    local f="$crit/$1/new/estimates.json"
    [ "$start_stamp" -gt 0 ] && [ "$(stat -c %Y "$f")" -lt "$start_stamp" ]
}

fmt() {
    awk -v t="$1" 'BEGIN {
        if (t >= 1e9) printf "%.3f s", t / 1e9;
        else if (t >= 1e6) printf "%.2f ms", t / 1e6;
        else if (t >= 1e3) printf "%.2f us", t / 1e3;
        else printf "%.0f ns", t }'
}

# Bench ids in report order: the expected ones, then any other found under the group.
ids() {
    local group="$1"; shift
    local seen=" " id
    for id in "$@"; do
        seen="$seen$id "
        echo "$group/$id"
    done
    if [ -d "$crit/$group" ]; then
        for d in "$crit/$group"/*/; do
            id=$(basename "$d")
            [ "$id" = report ] && continue
            case "$seen" in *" $id "*) continue ;; esac
            echo "$group/$id"
        done
    fi
}

# bar_ns for ids with a speed bar.
bar_ns() {
    case "$1" in
        optimize/k20_n15000) echo 30e6 ;;
        pipeline/*) echo 0.5e9 ;;
        *) echo "" ;;
    esac
}

echo
echo "| bench | median | bar | notes |"
echo "|---|---:|---:|---|"
prev=""
prev_id=""
{
    ids sampling bunny_20k
    ids optimize k20_n15000
    ids pipeline auto_bunny_20k
    ids assign threads_1 threads_2
    ids scaling_n 10k 100k 1M
    ids scaling_k 8 16 32 64
} | while read -r id; do
    m=$(median_ns "$id")
    if [ -z "$m" ]; then
        echo "| \`$id\` | - | | not measured |"
        prev=""
        continue
    fi
    bar=$(bar_ns "$id")
    notes=""
    status=""
    if [ -n "$bar" ]; then
        status=$(awk -v m="$m" -v b="$bar" 'BEGIN { print (m <= b) ? "ok" : "OVER" }')
        bar_txt=$(fmt "$bar")
        bar_txt="<= $bar_txt"
        notes="$status"
    else
        bar_txt=""
    fi
    group=${id%%/*}
    if [ -n "$prev" ] && [ "${prev_id%%/*}" = "$group" ]; then
        case "$group" in
            scaling_n|scaling_k)
                notes=$(awk -v a="$prev" -v b="$m" 'BEGIN { printf "x%.2f vs previous", b / a }') ;;
            assign)
                s=$(awk -v a="$prev" -v b="$m" 'BEGIN { printf "%.2f", a / b }')
                ok=$(awk -v s="$s" 'BEGIN { print (s >= 1.6) ? "ok" : "UNDER" }')
                notes="speedup ${s}x vs threads_1 (bar >= 1.6x): $ok" ;;
        esac
    fi
    if is_old "$id"; then notes="${notes:+$notes, }(old)"; fi
    echo "| \`$id\` | $(fmt "$m") | $bar_txt | $notes |"
    prev=$m
    prev_id=$id
done

if [ -f "$log" ]; then
    info=$(grep -E '^(optimize/k20_n15000: mesh|pipeline/[^ ]+: ends with|assign: )' "$log" || true)
    if [ -n "$info" ]; then
        echo
        echo "$info" | sed 's/^/    /'
    fi
fi
if [ -n "$elapsed" ]; then
    echo
    printf 'full run: %dm%02ds (cargo bench --bench pipeline%s), %s cores, load before: %s\n' \
        $((elapsed / 60)) $((elapsed % 60)) "${filter:+ -- '$filter'}" "$(nproc)" "$load"
fi
