// The pieces of three.js flexshaft's mode viewer uses, bundled as one script that sets window.FS3.
export {
  WebGLRenderer, Scene, PerspectiveCamera, OrthographicCamera, BufferGeometry, BufferAttribute,
  Mesh, MeshPhongMaterial, MeshBasicMaterial, LineSegments, LineBasicMaterial, AmbientLight,
  DirectionalLight, Color, Vector3, Box3, Sphere, Group, CylinderGeometry, DoubleSide, ArrowHelper,
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
