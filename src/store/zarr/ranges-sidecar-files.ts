// A ranges sidecar (ranges-sidecar.ts reads them; the converter's
// `--ranges-only` writes them from zfpy) made from what a stream learnt:
// the brick ranges of a store of lossless chunks at the rate its bricks were
// compressed at, NaN for the bricks never read (their neighbourhoods stay
// needed). The same layout as the converter's: a Zarr v3 group with
// attributes `zfpzarr_ranges` and per level `ranges/<L>` float32
// [gz, gy, gx, 2] in one uncompressed chunk (a level with no known brick has
// no chunk: every value is the fill value, NaN). Returned as files (path in
// the store -> bytes) for whoever writes them (the CLI: a folder).
import type { ZfpStore } from './store.ts';

export interface SidecarFiles {
  files: Map<string, Uint8Array>;
  /** Bricks with a known range, and all bricks, over every level. */
  known: number;
  bricks: number;
}

const json = (v: unknown) => new TextEncoder().encode(`${JSON.stringify(v, null, 2)}\n`);

/** `ranges(L)`: [min, max] per brick of level L (NaN where unknown), or null when none is known. */
export function rangesSidecarFiles(store: ZfpStore, ranges: (level: number) => Float32Array | null): SidecarFiles {
  const source = store.source;
  if (!source) throw new Error(`${store.name}: a zfp store; its ranges are range arrays the converter writes, not a sidecar`);
  const files = new Map<string, Uint8Array>();
  let known = 0;
  let bricks = 0;
  const levels = store.levels.map((l) => {
    const [gx, gy, gz] = l.layout.chunkGrid;
    const n = gx * gy * gz;
    bricks += n;
    const r = ranges(l.index);
    if (r && r.length !== 2 * n) throw new RangeError(`${store.name} level ${l.index}: ${r.length / 2} ranges for ${n} bricks`);
    files.set(`ranges/${l.index}/zarr.json`, json(arrayMeta([gz, gy, gx, 2])));
    if (r) {
      for (let i = 0; i < r.length; i += 2) if (!Number.isNaN(r[i])) known++;
      // little-endian float32, C order over [gz, gy, gx, 2]: the brick index order, x fastest
      const bytes = new Uint8Array(r.byteLength);
      const view = new DataView(bytes.buffer);
      for (let i = 0; i < r.length; i++) view.setFloat32(4 * i, r[i], true);
      files.set(`ranges/${l.index}/c/0/0/0/0`, bytes);
    }
    const [x, y, z] = l.layout.dims;
    return { path: l.path, brick: l.layout.chunkEdge, grid: [gx, gy, gz], dims: [x, y, z] };
  });
  files.set('ranges/zarr.json', json({ zarr_format: 3, node_type: 'group', attributes: {} }));
  files.set(
    'zarr.json',
    json({
      zarr_format: 3,
      node_type: 'group',
      attributes: {
        zfpzarr_ranges: {
          source: store.name,
          rate: source.rate,
          time: source.time.index,
          channel: source.channel.index,
          levels,
          learnt: { known, bricks },
        },
      },
    }),
  );
  return { files, known, bricks };
}

function arrayMeta(shape: number[]) {
  return {
    zarr_format: 3,
    node_type: 'array',
    shape,
    data_type: 'float32',
    chunk_grid: { name: 'regular', configuration: { chunk_shape: shape } },
    chunk_key_encoding: { name: 'default', configuration: { separator: '/' } },
    fill_value: 'NaN',
    codecs: [{ name: 'bytes', configuration: { endian: 'little' } }],
    attributes: {},
  };
}
