// The vendored OrbitControls.js (tuckercodec/web/vendor/three/) is three 0.187.0's, unchanged,
// so its types are those of @types/three 0.187.0. viewer/viewer.js imports
// `../vendor/three/OrbitControls.js`; in this folder (tuckercodec/web through symbolic links,
// without the vendored scripts) that import finds this declaration instead of the script.
export * from 'three/examples/jsm/controls/OrbitControls.js';
