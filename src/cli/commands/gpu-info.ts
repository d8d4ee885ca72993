import { describeAdapter, limitsToObject } from '../../gpu/device.ts';
import type { CliCommand } from '../command.ts';

export const gpuInfoCommand: CliCommand = {
  name: 'gpu-info',
  summary: 'adapter, limits and features of the WebGPU device in use',
  usage: 'gpu-info',
  options: {},
  async run(ctx) {
    const gpu = await ctx.gpu();
    const limits = limitsToObject(gpu.limits);
    const features = [...gpu.device.features].sort();
    const result = { adapter: gpu.adapter, features, limits };
    console.log(`adapter:  ${describeAdapter(gpu.adapter)}`);
    console.log(`features: ${features.join(', ')}`);
    for (const key of [
      'maxStorageBufferBindingSize',
      'maxBufferSize',
      'maxComputeWorkgroupStorageSize',
      'maxComputeInvocationsPerWorkgroup',
      'maxComputeWorkgroupsPerDimension',
    ]) {
      console.log(`${key.padEnd(36)} ${limits[key]}`);
    }
    return result;
  },
};
