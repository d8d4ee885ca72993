// WebGPU start-up for every page (the main page and the examples): the
// device, with validation errors shown as messages, and a browser without
// WebGPU shown over the view, in words. A lost device is shown over the view
// too, unless the page recovers from it (`onLost`: the main page gets a new
// device and reopens what was on screen).
import { BROWSER_HELP, requestGpu, WebGpuUnavailableError, type GpuContext } from '../gpu/device.ts';
import { type Messages, showFatal } from './messages.ts';

/**
 * Requests the device; on failure shows the reason over `stage`, calls
 * `onFatal` and returns undefined. `onLost`: called when the device is lost
 * for any reason (a driver reset, or destroyed), instead of the fatal message.
 */
export async function startGpu(
  stage: HTMLElement,
  messages: Messages,
  label: string,
  onFatal: () => void = () => {},
  onLost?: (message: string) => void,
): Promise<GpuContext | undefined> {
  try {
    const gpu = await requestGpu(navigator.gpu, {
      label,
      onFailure: (f) => {
        if (f.kind === 'device-lost') {
          if (onLost) return; // reported through gpu.lost below
          onFatal();
          showFatal(stage, f.message);
        } else messages.show(`WebGPU ${f.kind} error: ${f.message}`);
      },
    });
    if (onLost) void gpu.lost.then((f) => onLost(f.message));
    return gpu;
  } catch (e) {
    onFatal();
    showFatal(stage, e instanceof WebGpuUnavailableError ? e.message : `Could not start WebGPU: ${(e as Error).message}. ${BROWSER_HELP}`);
    return undefined;
  }
}
