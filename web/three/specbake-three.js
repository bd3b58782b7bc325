// specbake's specular anti-aliasing in three.js (tested with three r187, npm three 0.187.0): a GLTFLoader
// plugin that reads SPECBAKE_specular_aa (base layer and clear coat), loads the baked KTX2 chains through
// the loader's KTX2Loader with trilinear filtering, and patches MeshStandardMaterial / MeshPhysicalMaterial
// so every light's specular uses specbake's default (specaa_filtered_alpha2_matrix + specaa_default_D +
// specaa_ggx_G2 for the base; the isotropic form for the clear coat) in place of three.js's
// geometryRoughness; where the bake wrote the _SPECAA_CURVATURE vertex attribute the per-pixel kernel comes
// from it (SPECAA_USE_CURVATURE), as in specbake's default rule. three.js is the application's own dependency ('three' in its import map or bundler).
//
//   import { SpecbakeSpecularAAPlugin, setSpecbakeSpecularAA } from './specbake-three.js';
//   const loader = new GLTFLoader().setKTX2Loader(ktx2Loader);
//   loader.register((parser) => new SpecbakeSpecularAAPlugin(parser));
//   const gltf = await loader.loadAsync('baked/scene.gltf');
//   setSpecbakeSpecularAA(someMaterial, false);   // opt one material out (true: back in)
//
// Details and what the patch does to environment lighting: web/three/README.md.
import { LinearFilter, LinearMipmapLinearFilter, LoaderUtils, NoColorSpace, ShaderChunk } from 'three';
import specaaInclude from './specaa_es.glsl.js';

export const EXTENSION_NAME = 'SPECBAKE_specular_aa';

// The three.js lines the patch replaces (lights_physical_fragment, r187): the base and coat roughness with
// geometryRoughness added, and the start of the base layer's direct specular BRDF.
const BASE_ROUGHNESS = `material.roughness = max( roughnessFactor, 0.045 );
material.roughness += geometryRoughness;
material.roughness = min( material.roughness, 1.0 );`;
const COAT_ROUGHNESS = `material.clearcoatRoughness = max( material.clearcoatRoughness, 0.045 );
	material.clearcoatRoughness += geometryRoughness;
	material.clearcoatRoughness = min( material.clearcoatRoughness, 1.0 );`;
const BRDF_GGX_START = `vec3 BRDF_GGX( const in vec3 lightDir, const in vec3 viewDir, const in vec3 normal, const in PhysicalMaterial material ) {
`;

// True when this three.js has the lines the patch replaces; a version that changed them is not patched
// (the material renders as three.js draws it, and a warning says why).
export function specbakePatchSupported() {
    return ShaderChunk.lights_physical_fragment.includes(BASE_ROUGHNESS) &&
        ShaderChunk.lights_physical_fragment.includes(COAT_ROUGHNESS) &&
        ShaderChunk.lights_physical_pars_fragment.includes(BRDF_GGX_START);
}

// Opts `material` in (enabled true) or out (false) of the patch; it recompiles on its next render. Only
// materials the plugin patched carry the state; returns false for any other.
export function setSpecbakeSpecularAA(material, enabled) {
    const state = material.userData.specbake;
    if (!state) return false;
    if (state.enabled !== enabled) {
        state.enabled = enabled;
        material.needsUpdate = true;
    }
    return true;
}

// The layer's chains to bind: the Sigma (or t) kernel when baked, the material keeping its roughness (the
// recommended binding); else the baked roughness where it replaces the material's. LEAN and the mean
// normal are not bound (the material's normal map stays three.js's).
function chooseBinding(layer) {
    if (!layer) return null;
    const outputs = layer.outputs ?? [];
    const kernel = outputs.find((o) => o.kind === 'kernel');
    if (kernel) return { kind: 'kernel', output: kernel, anisotropic: kernel.channels === 4 };
    const roughness = outputs.find((o) => o.kind === 'roughness');
    if (roughness && layer.roughnessReplaced) return { kind: 'roughness', output: roughness, channel: layer.roughnessChannel ?? 0 };
    return { kind: 'none' };
}

// Replace mode (`specbake bake --gltf-mode replace`) already put the filtered chains into the material's
// own normal and roughness textures: the layer's textures are no longer the ones the extension baked.
function isReplaceMode(materialDef, ext) {
    const base = ext.source?.normalTexture;
    if (base !== undefined && materialDef.normalTexture?.index !== base) return true;
    const coat = ext.clearcoat?.source?.clearcoatNormalTexture;
    const coatDef = materialDef.extensions?.KHR_materials_clearcoat?.clearcoatNormalTexture;
    return coat !== undefined && coatDef?.index !== coat;
}

const CHANNELS = ['r', 'g', 'b', 'a'];

function fragmentPrefix(state) {
    const lines = [];
    const base = state.base, coat = state.coat;
    if (base.kind === 'kernel') {
        lines.push('#define SPECAA_KERNEL_TEXTURE specbakeBaseTexture');
        if (base.anisotropic) lines.push('#define SPECAA_KERNEL_ANISOTROPIC');
    } else if (base.kind === 'roughness') {
        lines.push('#define SPECAA_ROUGHNESS_TEXTURE specbakeBaseTexture');
        lines.push(`#define SPECAA_ROUGHNESS_CHANNEL ${CHANNELS[base.channel]}`);
    }
    if (base.kind !== 'none') lines.push('uniform highp sampler2D specbakeBaseTexture;');
    if (state.curvature) lines.push('#define SPECAA_USE_CURVATURE', 'varying vec4 vSpecbakeCurvature;', 'varying vec4 vSpecbakeTangent;');
    if (coat) {
        lines.push('#define SPECBAKE_COAT');
        if (coat.kind === 'roughness') {
            lines.push('#define SPECBAKE_COAT_ROUGHNESS_TEXTURE');
            lines.push(`#define SPECBAKE_COAT_CHANNEL ${CHANNELS[coat.channel]}`);
            lines.push('uniform highp sampler2D specbakeCoatTexture;');
        }
    }
    return `${lines.join('\n')}\n${specaaInclude}
SpecaaSurface specbakeSurface;
vec3 specbakeA;
`;
}

// The base layer's direct specular: specbake's default NDF and G2 of the filtered matrix in the tangent frame
// of the shading normal, with three.js's Fresnel (and iridescence). BRDF = F D G2 / (4 |n.l| |n.v|).
const SPECBAKE_BRDF = `
vec3 specbake_BRDF_GGX( const in vec3 lightDir, const in vec3 viewDir, const in vec3 normal, const in PhysicalMaterial material ) {
	vec3 t = normalize( specbakeSurface.tangent - normal * dot( normal, specbakeSurface.tangent ) );
	vec3 b = cross( normal, t );
	b = dot( b, specbakeSurface.bitangent ) < 0.0 ? - b : b;
	mat3 toTangent = transpose( mat3( t, b, normal ) );
	vec3 halfDir = normalize( lightDir + viewDir );
	vec3 hT = toTangent * halfDir, lT = toTangent * lightDir, vT = toTangent * viewDir;
	vec3 F = F_Schlick( material.specularColorBlended, material.specularF90, saturate( dot( viewDir, halfDir ) ) );
	#ifdef USE_IRIDESCENCE
		F = mix( F, material.iridescenceFresnel, material.iridescence );
	#endif
	float D = specaa_default_D( hT, specbakeA, specbakeSurface );
	float G2 = specaa_ggx_G2( lT, vT, hT, specbakeA );
	return F * ( D * G2 / max( 4.0 * abs( lT.z ) * abs( vT.z ), EPSILON ) );
}
`;

const BASE_REPLACEMENT = `
#ifdef SPECBAKE_SPECULAR_AA
// three.js's own minimum for punctual lights (BRDF_GGX), the simulator's too: a mirror under a point light
// has no finite highlight.
specbakeSurface.roughness = max( roughnessFactor, 0.045 );
specbakeSurface.uv = SPECBAKE_BASE_UV;
specbakeSurface.normal = nonPerturbedNormal;
specbakeSurface.position = vec3( 0.0 );
#if defined( SPECBAKE_CURVATURE )
// The baked curvature (_SPECAA_CURVATURE, d in the TANGENT frame) over the pixel's footprint in view space,
// the curvature scaled to view-space length in the vertex shader; the TANGENT frame around the vertex normal.
specbakeSurface.position = - vViewPosition;
specbakeSurface.tangent = normalize( vSpecbakeTangent.xyz - nonPerturbedNormal * dot( nonPerturbedNormal, vSpecbakeTangent.xyz ) );
specbakeSurface.bitangent = cross( nonPerturbedNormal, specbakeSurface.tangent ) * vSpecbakeTangent.w;
#elif defined( USE_NORMALMAP_TANGENTSPACE ) || defined( USE_CLEARCOAT_NORMALMAP ) || defined( USE_ANISOTROPY )
specbakeSurface.tangent = tbn[ 0 ];
specbakeSurface.bitangent = tbn[ 1 ];
#else
// No tangent frame in three.js's shader (no tangent-space normal map): any frame around the normal; the
// matrix and the BRDF below use the same one.
specbakeSurface.tangent = normalize( cross( abs( nonPerturbedNormal.y ) < 0.99 ? vec3( 0.0, 1.0, 0.0 ) : vec3( 1.0, 0.0, 0.0 ), nonPerturbedNormal ) );
specbakeSurface.bitangent = cross( nonPerturbedNormal, specbakeSurface.tangent );
#endif
#ifdef SPECBAKE_CURVATURE
specbakeSurface.curvature = vSpecbakeCurvature;
#else
specbakeSurface.curvature = vec4( 0.0 );
#endif
// The direction to the eye (view space, as the normal): the half vector turns with it across the pixel.
specbakeSurface.view = isOrthographic ? vec3( 0.0, 0.0, 1.0 ) : normalize( vViewPosition );
specbakeA = specaa_filtered_alpha2_matrix( specbakeSurface );
// Environment, area lights and the multiple-scattering terms read material.roughness: the isotropic form
// with the pixel kernel of the environment's lookup direction (specaa_environment_roughness), which turns
// with the view less than a light's highlight does towards grazing.
material.roughness = clamp( specaa_environment_roughness( specbakeSurface ), 0.045, 1.0 );
#else
${BASE_ROUGHNESS}
#endif`;

// Starts on a new line: three.js's build strips the comment that ended the line before.
const COAT_REPLACEMENT = `
#if defined( SPECBAKE_SPECULAR_AA ) && defined( SPECBAKE_COAT )
	{
		#ifdef SPECBAKE_COAT_ROUGHNESS_TEXTURE
			float specbakeCoatA = specaa_alpha2_from_roughness( texture( specbakeCoatTexture, SPECBAKE_COAT_UV ).SPECBAKE_COAT_CHANNEL );
		#else
			float specbakeCoatA = specaa_alpha2_from_roughness( material.clearcoatRoughness );
		#endif
		// TK21 Eq. (6)-(7): the pixel kernel of the vertex normal added in projected space.
		float a = specaa_filter_projected_isotropic( specaa_sanitize_alpha2( specbakeCoatA ), specaa_pixel_kernel( specbakeSurface ) );
		material.clearcoatRoughness = clamp( specaa_roughness_from_alpha2( specaa_is_finite( a ) ? a : 1.0 ), 0.045, 1.0 );
	}
	#else
	${COAT_ROUGHNESS}
	#endif`;

// The vertex shader's part with the baked curvature: the attribute (GLTFLoader names it _specaa_curvature)
// and the TANGENT frame passed on in view space; the curvature (1 / object-space length) divided by the
// model-view's scale (the cube root of its determinant: exact for a uniform scale).
const VERTEX_DECLARATIONS = `#ifdef SPECBAKE_CURVATURE
attribute vec4 _specaa_curvature;
#ifndef USE_TANGENT
attribute vec4 tangent;
#endif
varying vec4 vSpecbakeCurvature;
varying vec4 vSpecbakeTangent;
#endif
`;
const VERTEX_CURVATURE = `
#ifdef SPECBAKE_CURVATURE
	vSpecbakeCurvature = vec4( _specaa_curvature.xy / pow( abs( determinant( mat3( modelViewMatrix ) ) ), 1.0 / 3.0 ), _specaa_curvature.zw );
	vSpecbakeTangent = vec4( normalize( ( modelViewMatrix * vec4( tangent.xyz, 0.0 ) ).xyz ), tangent.w );
#endif`;

function patchShader(shader, state) {
    // Whichever program compiles last, three.js keeps its uniforms for the material, also when it switches
    // back to a program compiled before (setSpecbakeSpecularAA): the textures are always among them.
    shader.uniforms.specbakeBaseTexture = { value: state.baseTexture };
    shader.uniforms.specbakeCoatTexture = { value: state.coatTexture };
    if (!state.enabled) return;
    shader.defines = { ...(shader.defines ?? {}), SPECBAKE_SPECULAR_AA: '',
        SPECBAKE_BASE_UV: state.baseUv, SPECBAKE_COAT_UV: state.coatUv };
    if (state.curvature) {
        shader.defines.SPECBAKE_CURVATURE = '';
        shader.vertexShader = VERTEX_DECLARATIONS + shader.vertexShader
            .replace('#include <project_vertex>', `#include <project_vertex>${VERTEX_CURVATURE}`);
    }
    const physical = ShaderChunk.lights_physical_fragment.replace(BASE_ROUGHNESS, BASE_REPLACEMENT)
        .replace(COAT_ROUGHNESS, COAT_REPLACEMENT);
    const pars = ShaderChunk.lights_physical_pars_fragment.replace(BRDF_GGX_START,
        `${SPECBAKE_BRDF}\n${BRDF_GGX_START}\t#ifdef SPECBAKE_SPECULAR_AA\n\t\treturn specbake_BRDF_GGX( lightDir, viewDir, normal, material );\n\t#endif\n`);
    shader.fragmentShader = fragmentPrefix(state) + shader.fragmentShader
        .replace('#include <lights_physical_fragment>', physical)
        .replace('#include <lights_physical_pars_fragment>', pars);
}

function patchMaterial(material, state) {
    material.userData.specbake = state;
    const previous = material.onBeforeCompile;
    material.onBeforeCompile = (shader, renderer) => {
        previous.call(material, shader, renderer);
        patchShader(shader, material.userData.specbake);
    };
    const previousKey = material.customProgramCacheKey;
    material.customProgramCacheKey = () => {
        const s = material.userData.specbake;
        const on = `${s.base.kind}${s.base.anisotropic ? 'A' : ''}${s.base.channel ?? ''}/${s.coat?.kind ?? '-'}` +
            `${s.coat?.channel ?? ''}/${s.baseUv}/${s.coatUv}/${s.curvature ? 'K' : '-'}`;
        return `${previousKey.call(material)}|specbake:${s.enabled ? on : 'off'}`;
    };
    material.needsUpdate = true;
}

// Trilinear filtering between the baked levels, the levels as baked, data not colour.
function asBakedChain(texture) {
    texture.minFilter = LinearMipmapLinearFilter;
    texture.magFilter = LinearFilter;
    texture.generateMipmaps = false;
    texture.colorSpace = NoColorSpace;
    texture.flipY = false;
    texture.needsUpdate = true;
    return texture;
}

export class SpecbakeSpecularAAPlugin {
    // options.enabled: the initial state of every patched material (default true).
    constructor(parser, options = {}) {
        this.parser = parser;
        this.name = EXTENSION_NAME;
        this.enabledByDefault = options.enabled ?? true;
        this.report = { patched: [], skipped: [] };  // material names, and why others were left alone
        this._chains = new Map();
    }

    _loadChain(output) {
        const key = output.uri ?? `bufferView:${output.bufferView}`;
        if (!this._chains.has(key)) {
            const ktx2 = this.parser.options.ktx2Loader;
            if (!ktx2) throw new Error(`${EXTENSION_NAME}: GLTFLoader has no KTX2Loader (setKTX2Loader)`);
            let promise;
            if (output.uri !== undefined) {
                promise = ktx2.loadAsync(LoaderUtils.resolveURL(output.uri, this.parser.options.path));
            } else {
                promise = this.parser.getDependency('bufferView', output.bufferView)
                    .then((view) => new Promise((resolve, reject) => ktx2.parse(view.slice(0), resolve, reject)));
            }
            this._chains.set(key, promise.then(asBakedChain));
        }
        return this._chains.get(key);
    }

    // The binding with its chain loaded; a chain that is not KTX2, or a layer whose normal map three.js did
    // not get (the chains are in its UV space), binds no baked data, with a warning naming the material.
    async _layerState(binding, hasNormalMap, name) {
        if (!binding) return null;
        if (binding.kind === 'none') return { ...binding, texture: null };
        const why = binding.output.format !== 'ktx2' ? `its ${binding.output.format} ${binding.kind} chain is not loaded (bake KTX2)`
            : !hasNormalMap ? 'the material has no normal map, whose UV the baked chains use' : '';
        if (why) {
            console.warn(`${EXTENSION_NAME}: ${name}: ${why}; the pixel kernel alone filters it`);
            return { kind: 'none', texture: null };
        }
        return { ...binding, texture: await this._loadChain(binding.output) };
    }

    // The chains repeat or clamp as the normal map whose UV space they were baked in (glTF's default sampler
    // repeats; KTX2Loader's textures clamp): UVs outside [0, 1] read the texels the normal map reads.
    static _wrapLike(texture, normalMap) {
        if (!texture || !normalMap) return;
        if (texture.wrapS !== normalMap.wrapS || texture.wrapT !== normalMap.wrapT) {
            texture.wrapS = normalMap.wrapS;
            texture.wrapT = normalMap.wrapT;
            texture.needsUpdate = true;
        }
    }

    async afterRoot(result) {
        const json = this.parser.json;
        // Each material's meshes: the baked curvature is read where every one of them has it (and TANGENT,
        // the frame its principal direction is given in).
        const materials = new Map();
        for (const scene of result.scenes ?? [result.scene]) {
            scene.traverse((object) => {
                if (!object.isMesh) return;
                const attributes = object.geometry?.attributes ?? {};
                const curved = !!attributes._specaa_curvature && !!attributes.tangent;
                for (const m of Array.isArray(object.material) ? object.material : [object.material])
                    materials.set(m, (materials.get(m) ?? true) && curved);
            });
        }
        const pending = [];
        for (const [material, curvature] of materials) {
            const index = this.parser.associations.get(material)?.materials;
            const def = index === undefined ? null : json.materials?.[index];
            const ext = def?.extensions?.[EXTENSION_NAME];
            if (!ext) continue;
            const name = material.name || `material ${index}`;
            if (!material.isMeshStandardMaterial) {
                this.report.skipped.push({ name, reason: `${material.type} has no specular to patch` });
                continue;
            }
            if (isReplaceMode(def, ext)) {
                this.report.skipped.push({ name, reason: 'replace mode: the filtered chains are the material\'s own textures' });
                continue;
            }
            if (material.anisotropy > 0) {
                this.report.skipped.push({ name, reason: 'KHR_materials_anisotropy is not combined with the filtered matrix' });
                continue;
            }
            if (!specbakePatchSupported()) {
                this.report.skipped.push({ name, reason: 'this three.js changed the shader lines the patch replaces' });
                continue;
            }
            pending.push(this._patch(material, ext, name, curvature));
        }
        await Promise.all(pending);
        for (const s of this.report.skipped) console.warn(`${EXTENSION_NAME}: ${s.name} not patched: ${s.reason}`);
    }

    async _patch(material, ext, name, curvature) {
        // Base layer: baked only when the extension has its properties; a patched material always filters the
        // base with the pixel kernel of the vertex normal (the include's default without baked data).
        const base = await this._layerState(ext.outputs ? chooseBinding(ext) : { kind: 'none' }, !!material.normalMap, name);
        // The coat binds its baked roughness only (the include's textures are the base's); without one, its
        // own roughness is filtered by the pixel kernel.
        const coatRoughness = (ext.clearcoat?.outputs ?? []).find((o) => o.kind === 'roughness');
        const coatLayer = !ext.clearcoat ? null
            : coatRoughness && ext.clearcoat.roughnessReplaced
                ? { kind: 'roughness', output: coatRoughness, channel: ext.clearcoat.roughnessChannel ?? 0 }
                : { kind: 'none' };
        const coat = material.isMeshPhysicalMaterial && material.clearcoat > 0
            ? await this._layerState(coatLayer, !!material.clearcoatNormalMap, `${name} (clear coat)`) : null;
        SpecbakeSpecularAAPlugin._wrapLike(base.texture, material.normalMap);
        SpecbakeSpecularAAPlugin._wrapLike(coat?.texture, material.clearcoatNormalMap);
        patchMaterial(material, {
            enabled: this.enabledByDefault,
            base: { kind: base.kind, anisotropic: base.anisotropic, channel: base.channel },
            coat: coat ? { kind: coat.kind, channel: coat.channel } : null,
            baseTexture: base.texture, coatTexture: coat?.texture ?? null,
            curvature,
            baseUv: material.normalMap ? 'vNormalMapUv' : 'vec2( 0.0 )',
            coatUv: material.clearcoatNormalMap ? 'vClearcoatNormalMapUv' : 'vec2( 0.0 )',
        });
        this.report.patched.push(name);
    }
}
