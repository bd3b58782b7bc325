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

# name|defines (space-separated, passed as -D)
entries=(
  "none|SPECAA_COST_NONE"
  "slope|SPECAA_COST_SLOPE"
  "slope-aa|SPECAA_COST_SLOPE_AA"
  "projected-approx|SPECAA_COST_PROJECTED_APPROX"
  "projected-aa|SPECAA_COST_PROJECTED_AA"
  "projected|SPECAA_COST_PROJECTED"
  "iso-max|SPECAA_COST_ISO_MAX"
  "iso-sum|SPECAA_COST_ISO_SUM"
  "iso-mean|SPECAA_COST_ISO_MEAN"
  "curvature|SPECAA_COST_CURVATURE"
  "ggx-D|SPECAA_COST_GGX_D"
  "ggx-G2|SPECAA_COST_GGX_G2"
  "beckmann-D|SPECAA_COST_BECKMANN_D"
  "convolved-D (default NDF)|SPECAA_COST_CONVOLVED_D"
  "filtered-D (tail mixture)|SPECAA_COST_FILTERED_D"
  "isotropic default (derivatives only)|SPECAA_COST_DEFAULT"
  "isotropic default + kernel texture|SPECAA_COST_DEFAULT SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0"
  "isotropic default + roughness texture|SPECAA_COST_DEFAULT SPECAA_COST_TEXTURES SPECAA_ROUGHNESS_TEXTURE=uBaked0"
  "isotropic default + LEAN|SPECAA_COST_DEFAULT SPECAA_COST_TEXTURES SPECAA_LEAN_TEXTURE0=uBaked0 SPECAA_LEAN_TEXTURE1=uBaked1"
  "isotropic default + kernel + curvature|SPECAA_COST_DEFAULT SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0 SPECAA_USE_CURVATURE"
  "default (matrix, derivatives only)|SPECAA_COST_DEFAULT_MATRIX"
  "default (matrix) + kernel|SPECAA_COST_DEFAULT_MATRIX SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0"
  "default (matrix) + Sigma kernel|SPECAA_COST_DEFAULT_MATRIX SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0 SPECAA_KERNEL_ANISOTROPIC"
  "default (matrix) + LEAN|SPECAA_COST_DEFAULT_MATRIX SPECAA_COST_TEXTURES SPECAA_LEAN_TEXTURE0=uBaked0 SPECAA_LEAN_TEXTURE1=uBaked1"
  "default matrix + specaa_default_D (derivatives only)|SPECAA_COST_DEFAULT_NDF"
  "default matrix + specaa_default_D + kernel|SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0"
  "default matrix + specaa_default_D + Sigma kernel|SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0 SPECAA_KERNEL_ANISOTROPIC"
  "default matrix + specaa_default_D + Sigma kernel, two lobes|SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES SPECAA_KERNEL_TEXTURE=uBaked0 SPECAA_KERNEL_ANISOTROPIC SPECAA_KERNEL_TWO_LOBES"
  "default matrix + specaa_default_D + roughness texture|SPECAA_COST_DEFAULT_NDF SPECAA_COST_TEXTURES SPECAA_ROUGHNESS_TEXTURE=uBaked0"
  "mean normal texture (RGBA8)|SPECAA_COST_MEAN_NORMAL SPECAA_COST_TEXTURES"
  "mean normal texture (BC5, z rebuilt)|SPECAA_COST_MEAN_NORMAL SPECAA_COST_TEXTURES SPECAA_NORMAL_TWO_CHANNEL"
  "glints (C21, one light)|SPECAA_COST_GLINT"
  "glints + slope LEAN (one light)|SPECAA_COST_GLINT SPECAA_COST_TEXTURES"
  "glints, GGX target (one light)|SPECAA_COST_GLINT SPECAA_GLINT_GGX"
)

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
