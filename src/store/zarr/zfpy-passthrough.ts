// zarrita has no zfp codec, and we want none on the CPU: chunk bytes go to
// the GPU as they are stored (decoding stays in WGSL). zarrita's sanctioned
// extension point for codecs is its registry, so "numcodecs.zfpy" is
// registered as a pass-through array-to-bytes codec: `Array.getChunk` then
// returns the chunk's encoded bytes, for plain arrays and for inner chunks
// of `sharding_indexed` shards alike (zarrita reads the shard index, with
// its crc32c, and fetches just the inner chunk's byte range). A missing
// chunk comes back from zarrita as a typed array of the fill value instead,
// so a Uint8Array result is always stored bytes.
import * as zarr from 'zarrita';

export const ZFPY_CODEC = 'numcodecs.zfpy';
/** numcodecs.zfpy's `mode` for fixed rate (zfpy.mode_fixed_rate). */
export const ZFPY_FIXED_RATE_MODE = 2;

type CodecLoader = Parameters<typeof zarr.registry.set>[1];

/** The encoded chunk, as zarrita hands it on: bytes, one dimension. */
interface RawChunk {
  data: Uint8Array;
  shape: number[];
  stride: number[];
}

const passThrough = {
  kind: 'array_to_bytes' as const,
  fromConfig() {
    return {
      kind: 'array_to_bytes' as const,
      decode(bytes: Uint8Array): RawChunk {
        return { data: bytes, shape: [bytes.length], stride: [1] };
      },
      encode(): never {
        throw new Error('numcodecs.zfpy: this reader does not write chunks (the converter does: npm run convert)');
      },
    };
  },
};

/** Idempotent; the registry is zarrita's module-wide one. */
export function registerZfpyPassThrough(): void {
  zarr.registry.set(ZFPY_CODEC, (async () => passThrough) as unknown as CodecLoader);
}
