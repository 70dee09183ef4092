// An independent player for tests/anim_threejs.rs: loads glTF files with
// three.js's GLTFLoader and poses them with its AnimationMixer at given
// times, under Node (no browser). Reads a JSON request on stdin,
//   [{ "file": "...", "clip": null | "name", "times": [t, ...] }, ...]
// and writes per file and time each glTF node's world matrix
// (column-major), its morph weights, and the deformed vertex positions of
// its mesh (morph targets and skinning; three.js's getVertexPosition).
//
// Each time is posed from a fresh load and a fresh mixer: every action
// plays once and holds its last frame (LoopOnce + clampWhenFinished), so
// times past a clip's end are not wrapped by three.js's default looping.

import { readFileSync } from 'node:fs';
import { AnimationMixer, LoopOnce, Vector3 } from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

// three.js's FileLoader (which reads the data: URIs through fetch) reports
// progress with the browser's ProgressEvent, which Node lacks.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

function load(file) {
  // Buffers are embedded as data: URIs, which Node's fetch reads.
  const text = readFileSync(file, 'utf8');
  return new Promise((resolve, reject) => new GLTFLoader().parse(text, '', resolve, reject));
}

// The first mesh of a glTF node's object: the object itself for a node
// with a one-primitive mesh, else a child three.js made per primitive
// (children that are glTF nodes themselves do not count).
function meshOf(object, associations) {
  if (object.isMesh) return object;
  const primitive = (child) => child.isMesh && associations.get(child)?.nodes === undefined;
  return object.children.find(primitive) ?? null;
}

async function pose(file, clipName, time) {
  const gltf = await load(file);
  const mixer = new AnimationMixer(gltf.scene);
  const clips = gltf.animations.filter((clip) => clipName === null || clip.name === clipName);
  for (const clip of clips) {
    const action = mixer.clipAction(clip);
    action.setLoop(LoopOnce, 1);
    action.clampWhenFinished = true;
    action.play();
  }
  mixer.update(time);
  gltf.scene.updateMatrixWorld(true);

  const nodes = [];
  gltf.scene.traverse((object) => {
    const index = gltf.parser.associations.get(object)?.nodes;
    if (index === undefined) return;
    const node = { index, world: object.matrixWorld.toArray() };
    const mesh = meshOf(object, gltf.parser.associations);
    if (mesh && mesh.morphTargetInfluences) node.weights = Array.from(mesh.morphTargetInfluences);
    if (mesh) {
      const count = mesh.geometry.attributes.position.count;
      const vertex = new Vector3();
      node.positions = [];
      for (let i = 0; i < count; i++) {
        mesh.getVertexPosition(i, vertex);
        node.positions.push([vertex.x, vertex.y, vertex.z]);
      }
    }
    nodes.push(node);
  });
  nodes.sort((a, b) => a.index - b.index);
  return { time, nodes };
}

const request = JSON.parse(readFileSync(0, 'utf8'));
const answer = [];
for (const { file, clip, times } of request) {
  const samples = [];
  for (const time of times) samples.push(await pose(file, clip ?? null, time));
  answer.push({ file, samples });
}
process.stdout.write(JSON.stringify(answer));
