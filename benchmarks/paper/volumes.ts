// The volumes of `npm run bench:paper`: the shared ones (fuel 64^3, hydrogen
// atom 128^3, bonsai 256^3) and any given with --volume. Each becomes a zfp
// stream on the GPU (zfp files as they are; raw volumes compressed on the GPU)
// and its decoded float32 field, which every method contours, so serial,
// naive GPU and block-compressed marching cubes compute the same surfaces.
import { writeFileSync } from 'node:fs';
import { basename, join } from 'node:path';
import { readFileSync } from 'node:fs';
import type { GpuContext } from '../../src/gpu/device.ts';
import { describeOpenedVolume, openVolumeBytes } from '../../src/volume/open-volume.ts';
import type { Dims3 } from '../../src/mc/serial-mc.ts';
import { interestingRange } from '../../src/examples/paper-bench/measure.ts';
import type { ZfpDecoder } from '../../src/zfp/decoder.ts';
import type { ZfpGpuStream } from '../../src/zfp/gpu-stream.ts';

export interface VolumeSpec {
  key: string;
  label: string;
  path: string;
  /** Isovalue range of interest; undefined: from the data (interestingRange). */
  range?: [number, number];
  rangeSource?: string;
  /** The paper's name for this data set, where it reports it. */
  paperName?: 'Fuel' | 'Hydr.' | 'Bonsai';
}

export interface PreparedVolume extends VolumeSpec {
  dims: Dims3;
  how: string;
  rate: number;
  stream: ZfpGpuStream;
  /** The decoded field (x fastest), what every method contours. */
  values: Float32Array;
  range: [number, number];
  rangeSource: string;
  /** The data-driven range, also for volumes with a chosen one (for the report). */
  dataRange: [number, number];
  /** The decoded field as raw float32 (native binary, the browser page). */
  rawPath: string;
  /** The stream the GPU methods use, as a zfp file with header (the page's WebGPU runs); absent for header-less input. */
  zfpPath?: string;
}

/**
 * The shared volumes. Ranges: the span of each volume's reference isovalues in
 * shared/data/reference/mc_spec.json, picked per data set to cover its
 * surfaces of interest (no noise at the low end, no near-empty surfaces at
 * the top), like the paper's ranges.
 */
export function sharedVolumes(sharedData: string): VolumeSpec[] {
  const spec = JSON.parse(readFileSync(join(sharedData, 'reference', 'mc_spec.json'), 'utf8')) as {
    volumes: { file: string; isovalues: number[] }[];
  };
  const span = (file: string): [number, number] => {
    const v = spec.volumes.find((x) => x.file === file);
    if (!v) throw new Error(`mc_spec.json has no ${file}`);
    return [Math.min(...v.isovalues), Math.max(...v.isovalues)];
  };
  const src = 'span of the reference isovalues (mc_spec.json)';
  return [
    {
      key: 'fuel',
      label: 'Fuel 64³',
      path: join(sharedData, 'volumes', 'fuel_64x64x64_float32.raw'),
      range: span('volumes/fuel_64x64x64_float32.raw'),
      rangeSource: src,
      paperName: 'Fuel',
    },
    {
      key: 'hydrogen',
      label: 'Hydrogen atom 128³',
      path: join(sharedData, 'volumes', 'hydrogen_atom_128x128x128_float32.rate8.zfp'),
      range: span('volumes/hydrogen_atom_128x128x128_float32.rate8.zfp'),
      rangeSource: src,
      paperName: 'Hydr.',
    },
    {
      key: 'bonsai',
      label: 'Bonsai 256³',
      path: join(sharedData, 'volumes', 'bonsai_256x256x256_float32.rate4.zfp'),
      range: span('volumes/bonsai_256x256x256_float32.rate4.zfp'),
      rangeSource: src,
      paperName: 'Bonsai',
    },
  ];
}

/** `--volume FILE` or `--volume FILE:lo,hi`. */
export function userVolume(arg: string): VolumeSpec {
  const m = /^(.*):(-?[\d.eE+-]+),(-?[\d.eE+-]+)$/.exec(arg);
  const path = m ? m[1] : arg;
  const range: [number, number] | undefined = m ? [Number(m[2]), Number(m[3])] : undefined;
  if (range && !(range[0] < range[1])) throw new Error(`--volume ${arg}: the range must be lo,hi with lo < hi`);
  const name = basename(path);
  return {
    key: name.replace(/[^A-Za-z0-9]+/g, '-').toLowerCase(),
    label: name,
    path,
    range,
    rangeSource: range ? 'given with --volume' : undefined,
  };
}

/** Opens a volume on the GPU, decodes it once, and writes the decoded field to `dir`. */
export async function prepareVolume(
  gpu: GpuContext,
  decoder: ZfpDecoder,
  spec: VolumeSpec,
  dir: string,
  rate?: number,
): Promise<PreparedVolume> {
  const bytes = new Uint8Array(readFileSync(spec.path));
  const input = await openVolumeBytes(gpu.device, bytes, basename(spec.path), {
    reader: 'command',
    ...(rate === undefined ? {} : { rate }),
  });
  const dims = [...input.stream.info.dims] as Dims3;
  const values = (await decoder.readVolume(input.stream))!;
  const dataRange = interestingRange(values, dims);
  const rawPath = join(dir, `${spec.key}_${dims.join('x')}_float32.raw`);
  writeFileSync(rawPath, new Uint8Array(values.buffer, values.byteOffset, values.byteLength));
  let zfpPath: string | undefined;
  if (input.stream.info.hasHeader) {
    zfpPath = join(dir, `${spec.key}.stream.zfp`);
    writeFileSync(zfpPath, await input.stream.readBytes());
  }
  return {
    ...spec,
    dims,
    how: describeOpenedVolume(input),
    rate: input.rate,
    stream: input.stream,
    values,
    range: spec.range ?? dataRange,
    rangeSource: spec.rangeSource ?? 'from the data: 10th-90th percentile of the maxima of blocks spanning > 5% of the value range',
    dataRange,
    rawPath,
    zfpPath,
  };
}
