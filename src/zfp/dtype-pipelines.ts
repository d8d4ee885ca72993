// The kernels that read a source volume (the encoder, the error meter) take
// its type as an override constant (shaders/zfp/source_values.wgsl: no
// per-value switch): one pipeline per type, compiled once, on first use.
import type { DType } from '../core/dtype.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { WgslPart } from '../gpu/wgsl.ts';

/** DTYPE in source_values.wgsl. */
export const DTYPE_CODE: Record<DType, number> = { uint8: 0, int8: 1, uint16: 2, int16: 3, float32: 4, float64: 5 };

export class DtypePipelines {
  readonly #compiling = new Map<DType, Promise<GPUComputePipeline>>();
  readonly #ready = new Map<DType, GPUComputePipeline>();

  constructor(
    private readonly device: GPUDevice,
    private readonly label: string,
    private readonly code: WgslPart[],
    private readonly entryPoint: string,
    private readonly layout: GPUBindGroupLayout[],
  ) {}

  /** Compiles the pipeline for `dtype` (once; a failed compile is tried again next time). */
  prepare(dtype: DType): Promise<GPUComputePipeline> {
    let p = this.#compiling.get(dtype);
    if (!p) {
      p = createComputePipeline(this.device, `${this.label}.${dtype}`, this.code, this.entryPoint, {
        layout: this.layout,
        constants: { DTYPE: DTYPE_CODE[dtype] },
      }).then((pipeline) => {
        this.#ready.set(dtype, pipeline);
        return pipeline;
      });
      p.catch(() => this.#compiling.delete(dtype));
      this.#compiling.set(dtype, p);
    }
    return p;
  }

  /** The pipeline of `dtype` once prepare() has resolved, else undefined. */
  get(dtype: DType): GPUComputePipeline | undefined {
    return this.#ready.get(dtype);
  }
}
