// Reads a KTX2 file with ktx-parse (glTF-Transform's KTX2 reader: an independent check of
// uvpress's writer) and prints one JSON line: the header fields, the basic data format
// descriptor, the key/value data and the level index ({byteOffset, byteLength,
// uncompressedByteLength} per level, level 0 first, offsets in the file). With
// --astc-out PREFIX, every level's payload is also written as PREFIX<level>.astc, the .astc
// container of Arm's astcenc (16-byte header: magic, block footprint, size), so that the
// astcenc command decodes exactly what the KTX2 file holds.
// Usage: node ktx2-inspect.mjs FILE.ktx2 [--astc-out PREFIX]. Exit 0 when read, 2 when not.
import { readFile, writeFile } from 'node:fs/promises';
import { read } from 'ktx-parse';

const [file, flag, prefix] = process.argv.slice(2);
if (!file || (flag && (flag !== '--astc-out' || !prefix))) {
  console.error('usage: node ktx2-inspect.mjs FILE.ktx2 [--astc-out PREFIX]');
  process.exit(2);
}
try {
  const bytes = new Uint8Array(await readFile(file));
  const c = read(bytes);
  const dfd = c.dataFormatDescriptor[0];
  const levels = c.levels.map((l) => ({
    byteOffset: l.levelData.byteOffset - bytes.byteOffset,
    byteLength: l.levelData.byteLength,
    uncompressedByteLength: l.uncompressedByteLength,
  }));
  if (prefix) {
    const [bx, by] = [dfd.texelBlockDimension[0] + 1, dfd.texelBlockDimension[1] + 1];
    for (let i = 0; i < c.levels.length; i++) {
      const w = Math.max(1, c.pixelWidth >> i), h = Math.max(1, c.pixelHeight >> i);
      const header = new Uint8Array([0x13, 0xab, 0xa1, 0x5c, bx, by, 1,
        w & 255, (w >> 8) & 255, (w >> 16) & 255, h & 255, (h >> 8) & 255, (h >> 16) & 255, 1, 0, 0]);
      const out = new Uint8Array(16 + c.levels[i].levelData.byteLength);
      out.set(header, 0);
      out.set(c.levels[i].levelData, 16);
      await writeFile(`${prefix}${i}.astc`, out);
    }
  }
  const keyValue = {};
  for (const [k, v] of Object.entries(c.keyValue)) keyValue[k] = typeof v === 'string' ? v : Array.from(v);
  console.log(JSON.stringify({
    file, byteLength: bytes.byteLength,
    vkFormat: c.vkFormat, typeSize: c.typeSize, pixelWidth: c.pixelWidth, pixelHeight: c.pixelHeight,
    pixelDepth: c.pixelDepth, layerCount: c.layerCount, faceCount: c.faceCount, levelCount: c.levels.length,
    supercompressionScheme: c.supercompressionScheme,
    dfd: {
      vendorId: dfd.vendorId, descriptorType: dfd.descriptorType, versionNumber: dfd.versionNumber,
      colorModel: dfd.colorModel, colorPrimaries: dfd.colorPrimaries, transferFunction: dfd.transferFunction,
      flags: dfd.flags, texelBlockDimension: dfd.texelBlockDimension, bytesPlane: dfd.bytesPlane,
      samples: dfd.samples.map((s) => ({ bitOffset: s.bitOffset, bitLength: s.bitLength, channelType: s.channelType,
        sampleLower: s.sampleLower, sampleUpper: s.sampleUpper })),
    },
    keyValue, levels,
  }));
} catch (e) {
  console.error(`ktx2-inspect: ${file}: ${e.message ?? e}`);
  process.exit(2);
}
