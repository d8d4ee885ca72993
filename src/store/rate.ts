// The rate of a store of lossless chunks when none is asked for: issue 30's
// rule (src/zfp/rate-choice.ts) on a sample of the coarsest level's bricks,
// trials encoded and measured on the GPU, before any pool exists.
import type { GpuContext } from '../gpu/device.ts';
import { encoderFor } from '../zfp/encoder.ts';
import { chooseRate, describeRateChoice } from '../zfp/rate-choice.ts';
import { errorMeterFor } from '../zfp/stream-error.ts';
import type { OpenStoreOptions } from './zarr/open-store.ts';

export function storeRateChooser(gpu: GpuContext): NonNullable<OpenStoreOptions['chooseRate']> {
  return async (sample) => {
    const [encoder, meter] = await Promise.all([encoderFor(gpu.device), errorMeterFor(gpu.device)]);
    const c = await chooseRate(encoder, meter, sample.bytes, sample.dtype, sample.dims, { fileName: sample.name });
    return { rate: c.rate, description: describeRateChoice(c) };
  };
}
