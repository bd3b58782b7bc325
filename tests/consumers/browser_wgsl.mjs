// The page browser_check.mjs opens for WGSL jobs: for each entry of /job.json ({id, code, entryPoint?,
// render?: {vertex, fragment}, draw?: {size, texel}, inputs?, outputCount?}) it creates the shader module with WebGPU (Chromium's
// Tint, then Dawn on SwiftShader), reads getCompilationInfo, and with an entryPoint creates the compute
// pipeline (with render, a render pipeline of those two entry points, one rgba8unorm target); with inputs
// (floats) it binds them as a read-only storage buffer at @group(0) @binding(0), an output buffer of
// outputCount floats at @binding(1), dispatches ceil(outputCount / 4 / 64) workgroups of 64 and reads the
// outputs back (non-finite values as the strings "inf", "-inf", "nan": JSON has no such numbers); with draw
// it renders the module's vs/fs into a float target and reads it back (see draw()).
const post = (path, body) => fetch(path, { method: 'POST', body });

function encode(values) {
    return Array.from(values, (v) => (Number.isFinite(v) ? v : Number.isNaN(v) ? 'nan' : v > 0 ? 'inf' : '-inf'));
}

async function check(device, entry) {
    const result = { id: entry.id, errors: 0, messages: [], pipeline: false };
    device.pushErrorScope('validation');
    const module = device.createShaderModule({ code: entry.code });
    const info = await module.getCompilationInfo();
    for (const m of info.messages) {
        if (m.type === 'error') ++result.errors;
        result.messages.push({ type: m.type, line: m.lineNum, column: m.linePos, message: m.message });
    }
    let pipeline = null;
    if (entry.entryPoint) {
        try {
            pipeline = await device.createComputePipelineAsync({ layout: 'auto', compute: { module, entryPoint: entry.entryPoint } });
            result.pipeline = true;
        } catch (e) {
            result.pipelineError = String(e?.message ?? e);
        }
    }
    if (entry.render) {
        try {
            await device.createRenderPipelineAsync({
                layout: 'auto',
                vertex: { module, entryPoint: entry.render.vertex },
                fragment: { module, entryPoint: entry.render.fragment, targets: [{ format: 'rgba8unorm' }] },
            });
            result.pipeline = true;
        } catch (e) {
            result.pipelineError = String(e?.message ?? e);
        }
    }
    if (entry.draw) {
        try {
            result.pixels = encode(await draw(device, module, entry.draw));
        } catch (e) {
            result.drawError = String(e?.message ?? e);
        }
    }
    if (pipeline && entry.inputs) {
        const input = new Float32Array(entry.inputs.map((v) => (typeof v === 'string' ? Number(v.replace('nan', 'NaN').replace('inf', 'Infinity')) : v)));
        const inBuffer = device.createBuffer({ size: Math.max(16, input.byteLength), usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
        device.queue.writeBuffer(inBuffer, 0, input);
        const outBytes = 4 * entry.outputCount;
        const outBuffer = device.createBuffer({ size: outBytes, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
        const readBuffer = device.createBuffer({ size: outBytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
        const bindGroup = device.createBindGroup({
            layout: pipeline.getBindGroupLayout(0),
            entries: [{ binding: 0, resource: { buffer: inBuffer } }, { binding: 1, resource: { buffer: outBuffer } }],
        });
        const encoder = device.createCommandEncoder();
        const pass = encoder.beginComputePass();
        pass.setPipeline(pipeline);
        pass.setBindGroup(0, bindGroup);
        pass.dispatchWorkgroups(Math.ceil(entry.outputCount / 4 / 64));
        pass.end();
        encoder.copyBufferToBuffer(outBuffer, 0, readBuffer, 0, outBytes);
        device.queue.submit([encoder.finish()]);
        await readBuffer.mapAsync(GPUMapMode.READ);
        result.outputs = encode(new Float32Array(readBuffer.getMappedRange().slice(0)));
        readBuffer.unmap();
        for (const b of [inBuffer, outBuffer, readBuffer]) b.destroy();
    }
    const error = await device.popErrorScope();
    if (error) result.validationError = error.message;
    return result;
}

// draw: {size, texel: RGBA8 bytes}: the module's vs/fs entry points draw one full-screen triangle into a
// size x size rgba32float target with a 1 x 1 rgba8unorm texture of that texel at @binding(0) and a
// trilinear sampler at @binding(1) of @group(0); returns the target's floats, row 0 first.
async function draw(device, module, spec) {
    const pipeline = await device.createRenderPipelineAsync({
        layout: 'auto',
        vertex: { module, entryPoint: 'vs' },
        fragment: { module, entryPoint: 'fs', targets: [{ format: 'rgba32float' }] },
    });
    const texture = device.createTexture({ size: [1, 1], format: 'rgba8unorm', usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST });
    device.queue.writeTexture({ texture }, new Uint8Array(spec.texel), { bytesPerRow: 4 }, [1, 1]);
    const sampler = device.createSampler({ magFilter: 'linear', minFilter: 'linear', mipmapFilter: 'linear' });
    const target = device.createTexture({ size: [spec.size, spec.size], format: 'rgba32float', usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
    const bytesPerRow = Math.ceil((16 * spec.size) / 256) * 256;
    const read = device.createBuffer({ size: bytesPerRow * spec.size, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const bindGroup = device.createBindGroup({
        layout: pipeline.getBindGroupLayout(0),
        entries: [{ binding: 0, resource: texture.createView() }, { binding: 1, resource: sampler }],
    });
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginRenderPass({ colorAttachments: [{ view: target.createView(), loadOp: 'clear', storeOp: 'store', clearValue: [0, 0, 0, 0] }] });
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, bindGroup);
    pass.draw(3);
    pass.end();
    encoder.copyTextureToBuffer({ texture: target }, { buffer: read, bytesPerRow }, [spec.size, spec.size]);
    device.queue.submit([encoder.finish()]);
    await read.mapAsync(GPUMapMode.READ);
    const bytes = read.getMappedRange();
    const out = [];
    for (let y = 0; y < spec.size; ++y) out.push(...new Float32Array(bytes, y * bytesPerRow, 4 * spec.size));
    read.unmap();
    for (const r of [texture, target, read]) r.destroy();
    return out;
}

async function main() {
    const job = await (await fetch('/job.json')).json();
    if (!navigator.gpu) throw new Error('no navigator.gpu: WebGPU is not enabled in this Chromium');
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) throw new Error('navigator.gpu.requestAdapter() returned null: no WebGPU adapter');
    const device = await adapter.requestDevice();
    const results = [];
    for (const entry of job.modules) results.push(await check(device, entry));
    const adapterInfo = adapter.info ?? {};
    await post('/result', JSON.stringify({
        adapter: `${adapterInfo.vendor ?? ''} ${adapterInfo.architecture ?? ''} ${adapterInfo.description ?? ''}`.trim(),
        userAgent: navigator.userAgent, results,
    }));
}
main().catch((e) => post('/result', JSON.stringify({ fatal: String(e?.stack ?? e) })));
