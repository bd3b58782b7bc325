// The page browser_check.mjs opens for shader jobs: for each entry of /job.json ({id, vertex, fragment}),
// compiles both stages and links them with WebGL 2 (Chromium's ANGLE translator and its backend), draws one
// full-screen triangle with the program (samplers on units 0-2, none bound: WebGL's incomplete-texture
// black) and reports the compile and link status, the info logs, any GL error and the pixel read back;
// entries with `lod` instead read back the include's LOD against the mip the sampler chose (readLods).
const post = (path, body) => fetch(path, { method: 'POST', body });

function check(gl, entry) {
    const logs = {};
    const compile = (type, source, name) => {
        const shader = gl.createShader(type);
        gl.shaderSource(shader, source);
        gl.compileShader(shader);
        const ok = gl.getShaderParameter(shader, gl.COMPILE_STATUS);
        logs[name] = gl.getShaderInfoLog(shader) ?? '';
        return { shader, ok };
    };
    const vs = compile(gl.VERTEX_SHADER, entry.vertex, 'vertex');
    const fs = compile(gl.FRAGMENT_SHADER, entry.fragment, 'fragment');
    const result = { id: entry.id, compiled: vs.ok && fs.ok, linked: false, logs };
    if (result.compiled) {
        const program = gl.createProgram();
        gl.attachShader(program, vs.shader);
        gl.attachShader(program, fs.shader);
        gl.bindAttribLocation(program, 0, 'aPosition');
        gl.linkProgram(program);
        result.linked = !!gl.getProgramParameter(program, gl.LINK_STATUS);
        logs.program = gl.getProgramInfoLog(program) ?? '';
        if (result.linked && entry.lod) {
            Object.assign(result, readLods(gl, program, entry.lod));
        } else if (result.linked) {
            gl.useProgram(program);
            for (const [name, unit] of [['uBaked0', 0], ['uBaked1', 1], ['uGlintDictionary', 2]]) {
                const at = gl.getUniformLocation(program, name);
                if (at) gl.uniform1i(at, unit);
            }
            gl.drawArrays(gl.TRIANGLES, 0, 3);
            const pixel = new Uint8Array(4);
            gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
            result.pixel = Array.from(pixel);
            result.glError = gl.getError();
        }
        gl.deleteProgram(program);
    }
    gl.deleteShader(vs.shader);
    gl.deleteShader(fs.shader);
    return result;
}

// entry.lod: the program's fragment shader writes (LOD the include computes, mip level the sampler read) for
// a texture whose level k holds k in R (RGBA8, k / 255, NEAREST_MIPMAP_NEAREST) into an RGBA32F target;
// returns both per pixel.
function readLods(gl, program, lod) {
    const texture = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, texture);
    for (let k = 0; k < lod.levels; ++k) {
        const n = Math.max(1, lod.size >> k);
        const texels = new Uint8Array(n * n * 4);
        for (let i = 0; i < n * n; ++i) texels.set([k, 0, 0, 255], 4 * i);
        gl.texImage2D(gl.TEXTURE_2D, k, gl.RGBA8, n, n, 0, gl.RGBA, gl.UNSIGNED_BYTE, texels);
    }
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST_MIPMAP_NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAX_LEVEL, lod.levels - 1);
    if (!gl.getExtension('EXT_color_buffer_float')) throw new Error('no EXT_color_buffer_float');
    const target = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, target);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, lod.viewport, lod.viewport);
    const fbo = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    gl.bindTexture(gl.TEXTURE_2D, texture);
    gl.viewport(0, 0, lod.viewport, lod.viewport);
    gl.useProgram(program);
    gl.uniform1i(gl.getUniformLocation(program, 'uLevels'), 0);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const pixels = new Float32Array(lod.viewport * lod.viewport * 4);
    gl.readPixels(0, 0, lod.viewport, lod.viewport, gl.RGBA, gl.FLOAT, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, gl.drawingBufferWidth, gl.drawingBufferHeight);
    gl.deleteFramebuffer(fbo);
    gl.deleteTexture(target);
    gl.deleteTexture(texture);
    const computed = [], sampled = [];
    for (let i = 0; i < pixels.length; i += 4) {
        computed.push(pixels[i]);
        sampled.push(Math.round(pixels[i + 1] * 255));
    }
    return { computed, sampled, glError: gl.getError() };
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    const canvas = document.createElement('canvas');
    canvas.width = canvas.height = 4;
    const gl = canvas.getContext('webgl2', { antialias: false, preserveDrawingBuffer: true });
    if (!gl) throw new Error('no WebGL 2 context');
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 0, 1, 3, -1, 0, 1, -1, 3, 0, 1]), gl.STATIC_DRAW);
    gl.enableVertexAttribArray(0);
    gl.vertexAttribPointer(0, 4, gl.FLOAT, false, 0, 0);
    const results = job.shaders.map((entry) => check(gl, entry));
    const debug = gl.getExtension('WEBGL_debug_renderer_info');
    await post('/result', JSON.stringify({
        webgl: gl.getParameter(gl.VERSION),
        glsl: gl.getParameter(gl.SHADING_LANGUAGE_VERSION),
        renderer: debug ? gl.getParameter(debug.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER),
        userAgent: navigator.userAgent, results,
    }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e) })));
