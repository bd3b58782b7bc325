// The page browser_check.mjs opens for shader jobs: for each entry of /job.json ({id, vertex, fragment}),
// compiles both stages and links them with WebGL 2 (Chromium's ANGLE translator and its backend), draws one
// full-screen triangle with the program (samplers on units 0-2, none bound: WebGL's incomplete-texture
// black) and reports the compile and link status, the info logs, any GL error and the pixel read back.
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
        if (result.linked) {
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
