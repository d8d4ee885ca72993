// Loaded with `node --import`: TypeScript through tsx, then `?raw` text
// imports (registered last so they run first).
import { register } from 'node:module';
import { register as registerTsx } from 'tsx/esm/api';

registerTsx();
register('./node-hooks.mjs', import.meta.url);
