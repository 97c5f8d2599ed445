#!/usr/bin/env bash
# Whole-process times of the short commands (`--version`, `models`, `modes quad`), of one
# `pendkit` binary or of two side by side.
#
#   benches/process-start.sh BINARY [OTHER_BINARY [ROUNDS [RUNS]]]
#
# Alternates the binaries ROUNDS times (default 4), RUNS processes per command and round
# (default 200), with `perf stat`, and prints one line per round, binary and command: the
# mean wall time, the mean CPU time and the page faults of one process. The machine's
# other work moves every figure, so compare two binaries only within one run of this
# script ("-" as OTHER_BINARY measures one). Needs `perf`.
set -euo pipefail
old=${1:?a pendkit binary}
new=${2:--}
rounds=${3:-4}
runs=${4:-200}
commands=("--version" "models" "modes quad")
printf '%-6s %-5s %-12s %9s %9s %7s\n' round which command "wall ms" "CPU ms" faults
for round in $(seq "$rounds"); do
    for which in old new; do
        binary=$old
        if [ "$which" = new ]; then
            [ "$new" = - ] && continue
            binary=$new
        fi
        for command in "${commands[@]}"; do
            # shellcheck disable=SC2086 # the command's words are its arguments
            perf stat -r "$runs" -e task-clock,page-faults "$binary" $command 2>&1 >/dev/null |
                awk -v round="$round" -v which="$which" -v command="$command" '
                    /task-clock/ { cpu = $1 }
                    /page-faults/ { faults = $1 }
                    /elapsed/ { wall = $1 * 1000 }
                    END { printf "%-6s %-5s %-12s %9.3f %9.3f %7s\n", round, which, command, wall, cpu, faults }'
        done
    done
done
