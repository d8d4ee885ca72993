// Counts a device's shader module and compute pipeline creations (the
// per-device pipeline cache must make a second Isosurface, decoder or scan
// compile nothing). Wraps the device's methods until restore().

export interface CompilationCounts {
  modules: number;
  pipelines: number;
  restore(): void;
}

export function countCompilations(device: GPUDevice): CompilationCounts {
  const names = ['createShaderModule', 'createComputePipeline', 'createComputePipelineAsync'] as const;
  const target = device as unknown as Record<string, unknown>;
  const counts: CompilationCounts = {
    modules: 0,
    pipelines: 0,
    restore() {
      for (const name of names) delete target[name];
    },
  };
  for (const name of names) {
    const original = (device[name] as (...a: unknown[]) => unknown).bind(device);
    target[name] = (...a: unknown[]) => {
      if (name === 'createShaderModule') counts.modules++;
      else counts.pipelines++;
      return original(...a);
    };
  }
  return counts;
}
