// What a TypeScript user of the npm package writes, type-checked by tests/test_npm_package.py
// with tsc (strict) in a project where the packed package is installed: the declarations the
// `types` conditions of its `exports` name must type this, and must refuse each line marked as
// an expected error (a declaration that had decayed to `any` would accept it, and tsc would then
// report the unused directive).

import { Clock, LoadingManager, Mesh, PerspectiveCamera, Scene, WebGLRenderer } from 'three';
import { DEFAULT_LIMITS, openTkc, TkcError, TkcFile } from 'tuckercodec';
import { DEFAULT_FRAME_RATE, TKCAnimation, TKCLoader } from 'tuckercodec/three';

export function decode(bytes: Uint8Array): Float32Array {
  let file: TkcFile;
  try {
    file = openTkc(bytes, { limits: { max_vertices: 1e6 } });
  } catch (error) {
    if (error instanceof TkcError) console.error(error.rule, error.kind);
    throw error;
  }
  const vertices: number = file.vertices + file.frames + file.faceCount;
  const index: Uint32Array = file.triangles();
  const exact: Float64Array = file.frame(0);
  console.log(vertices, index.length, exact.length, DEFAULT_LIMITS);
  // @ts-expect-error a frame is a number
  file.frameFloat32('0');
  return file.frameFloat32(file.frames - 1);
}

export async function play(renderer: WebGLRenderer, camera: PerspectiveCamera): Promise<TKCAnimation> {
  const loader = new TKCLoader(new LoadingManager())
    .setPath('/models/')
    .setRequestHeader({ Authorization: 'Bearer x' })
    .setWithCredentials(true)
    .setDecoderOptions({ simd: true });
  const animation = await loader.loadAsync('anim.tkc', (event: ProgressEvent) => console.log(event.loaded));
  const mesh: Mesh = animation.mesh;
  const scene = new Scene();
  scene.add(mesh);
  const clock = new Clock();
  renderer.setAnimationLoop(() => {
    animation.update(clock.getDelta());
    renderer.render(scene, camera);
  });
  const facts: number[] = [animation.frameCount, animation.frameRate, animation.frame, animation.time, animation.duration, DEFAULT_FRAME_RATE];
  console.log(facts, animation.file.names);
  animation.setFrame(0).update(0.5).loop = false;
  // @ts-expect-error setFrame takes a frame number
  animation.setFrame('3');
  // @ts-expect-error the animation has no such method
  animation.play();
  loader.load('anim.tkc', (loaded: TKCAnimation) => loaded.dispose(), undefined, (error: unknown) => console.error(error));
  loader.parse(new ArrayBuffer(0), (parsed) => scene.add(parsed.mesh));
  const parsed: TKCAnimation = await loader.parseAsync(new Uint8Array(0));
  return new TKCAnimation(parsed.file);
}
