import { defineConfig } from 'vite';
import { sharedDataPlugin } from './scripts/vite-shared-data.ts';
import { storesPlugin } from './scripts/vite-stores.ts';

export default defineConfig({
  // /data/ -> ../shared/data on the dev and preview servers (tests, ?url=); see the plugin.
  // /stores/ -> a local folder of Zarr stores, with Range and CORS (scripts/vite-stores.ts).
  plugins: [sharedDataPlugin(), storesPlugin()],
  build: {
    target: 'es2022',
    sourcemap: true,
    // Every page of the app (the example pages live next to index.html).
    rolldownOptions: {
      input: {
        main: 'index.html',
        lidar: 'lidar.html',
        neuron: 'neuron.html',
        paperBench: 'paper-bench.html',
      },
    },
  },
  // Module workers (src/store/decode/brick-worker.ts): zarrita loads its codecs with dynamic imports.
  worker: { format: 'es' },
  server: { port: 5173 },
  preview: { port: 4173 },
});
