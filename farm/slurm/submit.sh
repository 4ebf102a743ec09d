#!/usr/bin/env bash
# Submit a wpbgi job to Slurm: one bake, then frames x tiles as a job array of renders that
# waits for it (--dependency=afterok), then one assembly per frame that waits for them all.
# A render or assembly task that fails is requeued by Slurm (up to --retries times); every
# output is written to a temporary name and renamed, so a killed task leaves no partial file.
#
#   farm/slurm/submit.sh SCENE OUTDIR [--frames 1-100[:STEP]] [--tiles 2x2] [--threads N]
#       [--retries N] [--bake-args "..."] [--render-args "..."] [--wpbgi PATH]
#       [-- more sbatch options, e.g. --partition=render]
#
# Prints the three job ids (bake, render array, assembly array). docs/farm.md explains the
# steps and the rules for sharing the cache; farm/slurm/task.sh is what each task runs.
set -euo pipefail

usage() { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
[ $# -ge 2 ] || usage
scene=$(realpath "$1"); out=$(realpath -m "$2"); shift 2
frames=1 tiles=2x2 threads=0 retries=2 bake_args='' render_args='' wpbgi=$(command -v wpbgi || true)
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames=$2; shift 2 ;;
    --tiles) tiles=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --retries) retries=$2; shift 2 ;;
    --bake-args) bake_args=$2; shift 2 ;;
    --render-args) render_args=$2; shift 2 ;;
    --wpbgi) wpbgi=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option $1" >&2; usage ;;
  esac
done
[ -n "$wpbgi" ] || { echo "submit.sh: no wpbgi on PATH: give --wpbgi PATH" >&2; exit 2; }
wpbgi=$(realpath "$wpbgi")
[ -f "$scene" ] || { echo "submit.sh: no scene at $scene" >&2; exit 2; }

# FIRST-LAST[:STEP] or one FRAME, as `wpbgi render --frames` reads it.
if [[ "$frames" =~ ^([0-9]+)(-([0-9]+)(:([0-9]+))?)?$ ]]; then
  first=${BASH_REMATCH[1]} last=${BASH_REMATCH[3]:-${BASH_REMATCH[1]}} step=${BASH_REMATCH[5]:-1}
else
  echo "submit.sh: --frames takes FIRST-LAST[:STEP] or FRAME, not $frames" >&2; exit 2
fi
frame_list=$(seq "$first" "$step" "$last" | tr '\n' ' ')
[ -n "$frame_list" ] || { echo "submit.sh: --frames $frames holds no frame" >&2; exit 2; }
if [[ "$tiles" =~ ^([1-9][0-9]*)x([1-9][0-9]*)$ ]]; then
  columns=${BASH_REMATCH[1]} rows=${BASH_REMATCH[2]}
else
  echo "submit.sh: --tiles takes COLUMNSxROWS, not $tiles" >&2; exit 2
fi
frame_count=$(wc -w <<< "$frame_list")
render_count=$((frame_count * columns * rows))

mkdir -p "$out/tiles" "$out/logs"
task=$(realpath "$(dirname "$0")/task.sh")
export WPBGI_BIN="$wpbgi" WPBGI_SCENE="$scene" WPBGI_OUT="$out" WPBGI_FRAMES="$frame_list" \
  WPBGI_COLUMNS="$columns" WPBGI_ROWS="$rows" WPBGI_THREADS="$threads" \
  WPBGI_RETRIES="$retries" WPBGI_BAKE_ARGS="$bake_args" WPBGI_RENDER_ARGS="$render_args"
# A requeued task appends to its log, so that the failed attempt's lines stay there. With
# --threads N each task asks Slurm for N CPUs; without, it takes Slurm's default and runs as
# many threads as Slurm gives it (task.sh).
common=(--parsable --export=ALL --requeue --open-mode=append)
[ "$threads" != 0 ] && common+=(--cpus-per-task="$threads")
common+=("$@")
bake=$(sbatch "${common[@]}" --job-name=wpbgi-bake --output="$out/logs/bake-%j.log" \
  "$task" bake)
render=$(sbatch "${common[@]}" --job-name=wpbgi-render --dependency="afterok:$bake" \
  --array="0-$((render_count - 1))" --output="$out/logs/render-%A_%a.log" "$task" render)
assemble=$(sbatch "${common[@]}" --job-name=wpbgi-assemble --dependency="afterok:$render" \
  --array="0-$((frame_count - 1))" --output="$out/logs/assemble-%A_%a.log" "$task" assemble)
echo "$bake $render $assemble"
