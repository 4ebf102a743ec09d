#!/usr/bin/env bash
# One task of a wpbgi job on Slurm (submitted by farm/slurm/submit.sh, which sets the WPBGI_*
# variables): `bake`, `render` (array index = frame x tile) or `assemble` (array index =
# frame). On failure the task asks Slurm to requeue it, up to WPBGI_RETRIES times; its output
# is written atomically by wpbgi, so a killed attempt leaves nothing under the final name.
set -uo pipefail

kind=$1
# As many threads as CPUs Slurm gave the task, not every core of the node: --threads, else
# --cpus-per-task, else the job's CPUs on this node ("4", or "4(x2)").
threads=()
n=${WPBGI_THREADS:-0}
[ "$n" = 0 ] && n=${SLURM_CPUS_PER_TASK:-0}
[ "$n" = 0 ] && n=${SLURM_JOB_CPUS_PER_NODE%%[^0-9]*}
[ "${n:-0}" != 0 ] && threads=(--threads "$n")
read -r -a frames <<< "$WPBGI_FRAMES"
index=${SLURM_ARRAY_TASK_ID:-0}
cache="$WPBGI_OUT/scene.wpc"

case "$kind" in
  bake)
    # shellcheck disable=SC2086 # the extra options are split on purpose
    "$WPBGI_BIN" "${threads[@]}" bake "$WPBGI_SCENE" -o "$cache" $WPBGI_BAKE_ARGS ;;
  render)
    per_frame=$((WPBGI_COLUMNS * WPBGI_ROWS))
    frame=${frames[$((index / per_frame))]}
    tile=$((index % per_frame))
    column=$((tile % WPBGI_COLUMNS + 1)) row=$((tile / WPBGI_COLUMNS + 1))
    # shellcheck disable=SC2086
    "$WPBGI_BIN" "${threads[@]}" render "$WPBGI_SCENE" --cache "$cache" --frames "$frame" \
      --tile-grid "${WPBGI_COLUMNS}x${WPBGI_ROWS}" --tile "$column,$row" \
      -o "$WPBGI_OUT/tiles/beauty.\$F4.c${column}r${row}.exr" $WPBGI_RENDER_ARGS ;;
  assemble)
    printf -v frame '%04d' "${frames[$index]}"
    "$WPBGI_BIN" assemble -o "$WPBGI_OUT/beauty.$frame.exr" \
      "$WPBGI_OUT/tiles/beauty.$frame".c*r*.exr ;;
  *) echo "task.sh: unknown task kind $kind" >&2; exit 2 ;;
esac
status=$?
if [ "$status" != 0 ] && [ -n "${SLURM_JOB_ID:-}" ] \
   && [ "${SLURM_RESTART_COUNT:-0}" -lt "${WPBGI_RETRIES:-0}" ]; then
  echo "task.sh: $kind task $index failed ($status): requeued (attempt $((${SLURM_RESTART_COUNT:-0} + 2)))" >&2
  scontrol requeue "${SLURM_ARRAY_JOB_ID:-$SLURM_JOB_ID}${SLURM_ARRAY_TASK_ID:+_$SLURM_ARRAY_TASK_ID}"
  # Slurm ends this attempt; if it has not yet, stop here without failing the dependency.
  sleep 60
fi
exit "$status"
