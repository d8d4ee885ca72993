// Where the default view looks from: the camera fits to it, and the built-in
// volume opens its shells toward it, so the two must agree.

/** Where a y-up fit looks from (toward the centre): front, right, a little above. */
export const DEFAULT_VIEW_DIRECTION: readonly [number, number, number] = [0.62, 0.5, 1];
