// Scalar types of uncompressed volumes, as named in `name_XxYxZ_dtype.raw`.

export type DType = 'uint8' | 'int8' | 'uint16' | 'int16' | 'float32' | 'float64';

export const DTYPES: readonly DType[] = ['uint8', 'int8', 'uint16', 'int16', 'float32', 'float64'];

export const DTYPE_BYTES: Record<DType, number> = {
  uint8: 1,
  int8: 1,
  uint16: 2,
  int16: 2,
  float32: 4,
  float64: 8,
};

export function isDType(s: string): s is DType {
  return (DTYPES as readonly string[]).includes(s);
}

/** Typed view of little-endian raw bytes (copies when unaligned). */
export function typedView(dtype: DType, bytes: Uint8Array): ArrayLike<number> {
  const n = Math.floor(bytes.byteLength / DTYPE_BYTES[dtype]);
  const aligned = bytes.byteOffset % DTYPE_BYTES[dtype] === 0 ? bytes : bytes.slice();
  const { buffer, byteOffset } = aligned;
  switch (dtype) {
    case 'uint8':
      return new Uint8Array(buffer, byteOffset, n);
    case 'int8':
      return new Int8Array(buffer, byteOffset, n);
    case 'uint16':
      return new Uint16Array(buffer, byteOffset, n);
    case 'int16':
      return new Int16Array(buffer, byteOffset, n);
    case 'float32':
      return new Float32Array(buffer, byteOffset, n);
    case 'float64':
      return new Float64Array(buffer, byteOffset, n);
  }
}
