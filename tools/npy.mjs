// A NumPy .npy (version 1.0) file of little-endian float32, for the three.js tools
// (three_eval.mjs, three_source_eval.mjs) to hand positions to the Rust tests.

/**
 * The bytes of a .npy file holding `values` (a Float32Array) with `shape`.
 * @param {Float32Array} values
 * @param {number[]} shape
 * @returns {Buffer}
 */
export function npy(values, shape) {
  let header = `{'descr': '<f4', 'fortran_order': False, 'shape': (${shape.join(', ')}${shape.length === 1 ? ',' : ''}), }`;
  const unpadded = 10 + header.length + 1;
  header += ' '.repeat((64 - (unpadded % 64)) % 64) + '\n';
  const head = Buffer.alloc(10);
  head.write('\x93NUMPY', 0, 'latin1');
  head[6] = 1;
  head[7] = 0;
  head.writeUInt16LE(header.length, 8);
  const body = Buffer.from(values.buffer, values.byteOffset, values.byteLength);
  return Buffer.concat([head, Buffer.from(header, 'latin1'), body]);
}
