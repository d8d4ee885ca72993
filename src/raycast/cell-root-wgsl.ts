// WGSL side of cell-root.ts: the snippet a kernel composes in (no bindings).
import cellRootWgsl from '../../shaders/raycast/cell_root.wgsl?raw';
import type { WgslPart } from '../gpu/wgsl.ts';

export const cellRootSnippet: WgslPart = { name: 'shaders/raycast/cell_root.wgsl', code: cellRootWgsl };
