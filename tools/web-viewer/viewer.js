// The page script of om.export(scene, "scene.html"): three.js shows the scene's glTF (embedded as base64)
// with the scene's camera, lights and background, and orbit controls.  Bundled by ./build.sh into
// omnirender/export/assets/three_viewer.min.js, which omnirender/export/html.py inlines into every page.
import * as THREE from "three";
import { GLTFLoader } from "three/examples/jsm/loaders/GLTFLoader.js";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { RectAreaLightUniformsLib } from "three/examples/jsm/lights/RectAreaLightUniformsLib.js";

function decode(base64) {
  const text = atob(base64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  return bytes.buffer;
}

// omnirender lights follow OpenGL: a diffuse surface lit head-on by a light of intensity I has the colour
// I x albedo, and lights do not fall off with distance unless they have attenuation.  three.js lights are
// physical (a Lambertian BRDF albedo / pi, point lights falling off as 1 / d^decay), so intensities are
// multiplied by pi and point and spot lights get the decay of their attenuation (see html.py).
function convertLight(light, units) {
  light.intensity *= Math.PI;
  if (light.isPointLight || light.isSpotLight) {
    const [constant, linear, quadratic] = units.attenuation || [1, 0, 0];
    if (quadratic > 0) {
      light.decay = 2;
      light.intensity /= quadratic;
    } else if (linear > 0) {
      light.decay = 1;
      light.intensity /= linear;
    } else {
      light.decay = 0;
      light.intensity /= constant || 1;
    }
    light.distance = 0;
  }
  if (light.isSpotLight) light.penumbra = units.penumbra || 0;
}

// Materials and shadows as the GL engine draws them.  A Phong material (omnirender's om.Material, kept by the
// glTF exporter in the material's extras) becomes three.js's Blinn-Phong material: GL's Phong exponent n is
// about a Blinn-Phong exponent 4 n, and three.js normalises its lobe by (n / 2 + 1) and weighs it by the
// cosine of the light, which GL does not, so the specular colour is divided by that factor (the highlight's
// peak stays GL's; the metallic-roughness stand-in had a bright glare on rough floors).
function phongMaterial(material, phong) {
  const shininess = 4 * Math.max(phong.shininess, 1);
  const spec = phong.specular.map((c) => c / (shininess / 2 + 1));
  return new THREE.MeshPhongMaterial({
    name: material.name,
    color: material.color,
    map: material.map,
    specular: new THREE.Color(spec[0], spec[1], spec[2]),
    shininess,
    emissive: material.emissive,
    emissiveMap: material.emissiveMap,
    normalMap: material.normalMap,
    side: material.side,
    transparent: material.transparent,
    opacity: material.opacity,
    alphaTest: material.alphaTest,
    vertexColors: material.vertexColors,
  });
}

// om.RectLight / om.DiscLight: the glTF exporter writes a spot (KHR_lights_punctual has no area lights) with the
// area light in its extras; the page puts a three.js RectAreaLight in its place (radiance L is three.js's
// luminance: a diffuse surface shows albedo x L x form factor, the rule of every omnirender engine).  A disc
// becomes a square of its area, a two-sided light two lights back to back.  three.js's RectAreaLight casts no
// shadows and lights only physically based materials, so a scene with area lights gets MeshStandardMaterials
// for its Phong ones (the roughness of the Phong exponent, as omnirender's phong_roughness).
function areaLights(root) {
  const found = [];
  root.traverse((object) => {
    const record = ((object.userData || {}).omnirender || {}).area_light;
    if (object.isLight && record) found.push([object, record]);
  });
  if (found.length) RectAreaLightUniformsLib.init();
  for (const [spot, record] of found) {
    const width = record.shape === "disc" ? record.radius * Math.sqrt(Math.PI) : record.width;
    const height = record.shape === "disc" ? record.radius * Math.sqrt(Math.PI) : record.height;
    const sides = record.two_sided ? [0, Math.PI] : [0];
    for (const turn of sides) {
      const light = new THREE.RectAreaLight(spot.color, record.radiance, width, height);
      light.position.copy(spot.position);
      light.quaternion.copy(spot.quaternion);
      if (turn) light.rotateY(turn);
      spot.parent.add(light);
    }
    spot.parent.remove(spot);
  }
  return found.length > 0;
}

function standardMaterial(material, phong) {
  const roughness = Math.sqrt(Math.min(1, Math.max(0.01, Math.sqrt(2 / (4 * Math.max(phong.shininess, 1) + 2)))));
  return new THREE.MeshStandardMaterial({
    name: material.name,
    color: material.color,
    map: material.map,
    roughness,
    metalness: 0,
    emissive: material.emissive,
    emissiveMap: material.emissiveMap,
    normalMap: material.normalMap,
    side: material.side,
    transparent: material.transparent,
    opacity: material.opacity,
    alphaTest: material.alphaTest,
    vertexColors: material.vertexColors,
  });
}

// Shadow maps on, as in every omnirender engine: every opaque mesh casts and receives, every light casts,
// with 2048-texel maps, soft PCF, a normal bias of 0.6 % of the scene radius and a camera fitted to it.
function enableShadows(renderer, root) {
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFSoftShadowMap;
  const box = new THREE.Box3().setFromObject(root);
  const center = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  root.traverse((object) => {
    if (object.isMesh) {
      const materials = Array.isArray(object.material) ? object.material : [object.material];
      object.castShadow = !materials.some((m) => m.transparent);
      object.receiveShadow = true;
    }
    if (!object.isLight || object.isAmbientLight || object.isRectAreaLight) return;
    object.castShadow = true;
    object.shadow.mapSize.set(2048, 2048);
    object.shadow.bias = -0.0002;
    object.shadow.normalBias = radius * 0.006;
    const position = object.getWorldPosition(new THREE.Vector3());
    const far = position.distanceTo(center) + radius;
    if (object.isDirectionalLight) {
      const shadowCamera = object.shadow.camera;
      shadowCamera.left = shadowCamera.bottom = -radius;
      shadowCamera.right = shadowCamera.top = radius;
      // the shadow camera sits at the light and looks at its target (a child one unit ahead): the light is
      // moved along its direction to just behind the scene, which changes nothing else for a sun
      const d = object.target.getWorldPosition(new THREE.Vector3()).sub(position).normalize();
      const place = center.clone().addScaledVector(d, -2 * radius);
      if (object.parent) object.parent.worldToLocal(place);
      object.position.copy(place);
      object.updateMatrixWorld(true);
      shadowCamera.near = 0.01 * radius;
      shadowCamera.far = 4 * radius;
    } else {
      // a light exactly in the plane of a caster's face (round numbers: a light above a floor's edge) makes
      // SwiftShader's clipper fill a whole cube face with that edge-on face, shadowing everything in it:
      // the light moves by a ten-thousandth of the scene, which nothing else notices
      object.position.add(new THREE.Vector3(0.73, 0.31, 0.53).multiplyScalar(radius * 1e-4));
      object.updateMatrixWorld(true);
      object.shadow.camera.near = Math.max(far - 2 * radius, far * 0.002);
      object.shadow.camera.far = far;
    }
    object.shadow.camera.updateProjectionMatrix();
  });
}

function fittedCamera(root, aspect) {
  const box = new THREE.Box3().setFromObject(root);
  const center = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const camera = new THREE.PerspectiveCamera(35, aspect, radius / 100, radius * 100);
  camera.position.copy(center).add(new THREE.Vector3(0.6, 0.45, 1).normalize().multiplyScalar(radius * 3.3));
  camera.lookAt(center);
  return { camera, target: center };
}

export function show(container, options) {
  const width = () => container.clientWidth || window.innerWidth;
  const height = () => container.clientHeight || window.innerHeight;
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(width(), height());
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  const bg = options.background || [0, 0, 0, 1];
  scene.background = new THREE.Color().setRGB(bg[0], bg[1], bg[2], THREE.SRGBColorSpace);
  const status = (text) => {
    document.body.dataset.status = text;
  };
  new GLTFLoader().parse(
    decode(options.glb),
    "",
    (gltf) => {
      scene.add(gltf.scene);
      gltf.scene.updateMatrixWorld(true);
      const physical = areaLights(gltf.scene);
      let index = 0;
      gltf.scene.traverse((object) => {
        if (object.isLight && !object.isRectAreaLight) convertLight(object, (options.lights || [])[index++] || {});
        if (object.isMesh && !Array.isArray(object.material)) {
          const phong = ((object.material.userData || {}).omnirender || {}).phong;
          if (phong) object.material = (physical ? standardMaterial : phongMaterial)(object.material, phong);
        }
      });
      enableShadows(renderer, gltf.scene);
      const ambient = options.ambient || [0, 0, 0];
      if (ambient.some((v) => v > 0)) {
        const color = new THREE.Color().setRGB(ambient[0], ambient[1], ambient[2], THREE.SRGBColorSpace);
        scene.add(new THREE.AmbientLight(color, Math.PI));
      }
      let camera;
      let target;
      const found = gltf.cameras[0];
      if (found) {
        // a camera at the root (orbit controls move it in world space), placed where the scene's camera is
        camera = found.clone();
        found.matrixWorld.decompose(camera.position, camera.quaternion, camera.scale);
        camera.scale.set(1, 1, 1);
        const forward = new THREE.Vector3(0, 0, -1).applyQuaternion(camera.quaternion);
        target = camera.position.clone().addScaledVector(forward, options.distance || 1);
      } else {
        ({ camera, target } = fittedCamera(gltf.scene, width() / height()));
      }
      const frame = () => {
        const w = width();
        const h = height();
        renderer.setSize(w, h);
        if (camera.isOrthographicCamera) {
          const half = (camera.top - camera.bottom) / 2;
          camera.left = (-half * w) / h;
          camera.right = (half * w) / h;
        } else {
          camera.aspect = w / h;
        }
        camera.updateProjectionMatrix();
      };
      frame();
      const controls = new OrbitControls(camera, renderer.domElement);
      controls.target.copy(target);
      controls.update();
      const draw = () => renderer.render(scene, camera);
      controls.addEventListener("change", draw);
      window.addEventListener("resize", () => {
        frame();
        draw();
      });
      draw();
      status("ready");
    },
    (error) => {
      status("error");
      container.textContent = "omnirender: cannot show the scene: " + error;
    },
  );
}
