// WebGPU start-up for every page (the main page and the examples): the
// device, with validation errors shown as messages and a lost device or a
// browser without WebGPU shown over the view, in words.
import { BROWSER_HELP, requestGpu, WebGpuUnavailableError, type GpuContext } from '../gpu/device.ts';
import { type Messages, showFatal } from './messages.ts';

/** Requests the device; on failure shows the reason over `stage`, calls `onFatal` and returns undefined. */
export async function startGpu(
  stage: HTMLElement,
  messages: Messages,
  label: string,
  onFatal: () => void = () => {},
): Promise<GpuContext | undefined> {
  try {
    return await requestGpu(navigator.gpu, {
      label,
      onFailure: (f) => {
        if (f.kind === 'device-lost') {
          onFatal();
          showFatal(stage, f.message);
        } else messages.show(`WebGPU ${f.kind} error: ${f.message}`);
      },
    });
  } catch (e) {
    onFatal();
    showFatal(stage, e instanceof WebGpuUnavailableError ? e.message : `Could not start WebGPU: ${(e as Error).message}. ${BROWSER_HELP}`);
    return undefined;
  }
}
