#!/usr/bin/env bash
# Run-time cost of the include: SPIR-V instruction count of one fragment entry point per method after
# `spirv-opt -O`, for GLSL and HLSL. Counts the instruction lines inside functions of the spirv-dis output
# (OpFunction .. OpFunctionEnd, i.e. the executable code after inlining); "extra" subtracts the
# unfiltered baseline "none". Needs glslangValidator, spirv-opt, spirv-dis, spirv-val.
#   shaders/count_instructions.sh [--markdown]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
markdown=0
[[ "${1:-}" == "--markdown" ]] && markdown=1

# name|defines (space-separated, passed as -D), one entry point per line of cost/entries.list
entries=()
while IFS= read -r line; do
  [[ -z "$line" || "$line" == \#* ]] || entries+=("$line")
done <"$here/cost/entries.list"

# count LANG DEFINES -> number of instruction lines in functions after spirv-opt -O
count() {
  local lang="$1" defines="$2" args=() d
  for d in $defines; do args+=("-D$d"); done
  if [[ "$lang" == glsl ]]; then
    glslangValidator -G -S frag -I"$here" "${args[@]}" "$here/cost/entries.frag" -o "$work/in.spv" >"$work/log" 2>&1 \
      || { cat "$work/log" >&2; return 1; }
    env=opengl4.5
  else
    glslangValidator -V -D -e main -S frag -I"$here" "${args[@]}" "$here/cost/entries.hlsl" -o "$work/in.spv" >"$work/log" 2>&1 \
      || { cat "$work/log" >&2; return 1; }
    env=vulkan1.0
  fi
  spirv-opt -O "$work/in.spv" -o "$work/opt.spv"
  spirv-val --target-env "$env" "$work/opt.spv"
  spirv-dis --no-header --raw-id "$work/opt.spv" | awk '/OpFunction /{f=1} f&&/Op/{n++} /OpFunctionEnd/{f=0} END{print n+0}'
}

declare -A base
for lang in glsl hlsl; do base[$lang]=$(count "$lang" SPECAA_COST_NONE); done
if ((markdown)); then
  echo "| entry point | GLSL | GLSL extra | HLSL | HLSL extra |"
  echo "|---|---:|---:|---:|---:|"
else
  printf "%-30s %6s %6s %6s %6s\n" "entry point" glsl extra hlsl extra
fi
for e in "${entries[@]}"; do
  name="${e%%|*}"; defines="${e#*|}"
  g=$(count glsl "$defines"); h=$(count hlsl "$defines")
  if ((markdown)); then
    echo "| $name | $g | $((g - base[glsl])) | $h | $((h - base[hlsl])) |"
  else
    printf "%-30s %6d %6d %6d %6d\n" "$name" "$g" $((g - base[glsl])) "$h" $((h - base[hlsl]))
  fi
done
