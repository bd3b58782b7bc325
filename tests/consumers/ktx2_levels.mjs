// Reads a KTX2 file with ktx-parse (an independent reader) and writes what it found: a JSON summary on
// stdout and each level's stored bytes (as ktx-parse returns them) to <out>/level<N>.bin.
// Usage: node ktx2_levels.mjs FILE.ktx2 OUT_DIR
import { read } from 'ktx-parse';
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

const [file, out] = process.argv.slice(2);
const container = read(new Uint8Array(readFileSync(file)));
const dfd = container.dataFormatDescriptor[0];
const levels = container.levels.map((level, i) => {
    writeFileSync(join(out, `level${i}.bin`), level.levelData);
    return { byteLength: level.levelData.byteLength, uncompressedByteLength: level.uncompressedByteLength };
});
process.stdout.write(JSON.stringify({
    vkFormat: container.vkFormat,
    typeSize: container.typeSize,
    pixelWidth: container.pixelWidth,
    pixelHeight: container.pixelHeight,
    supercompressionScheme: container.supercompressionScheme,
    colorModel: dfd.colorModel,
    transferFunction: dfd.transferFunction,
    samples: dfd.samples.length,
    writer: container.keyValue.KTXwriter,
    levels,
}) + '\n');
