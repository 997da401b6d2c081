// GltfReplay.cpp — PlayResult → glTF 2.0 binary with tinygltf.
#include "brittle/player/GltfReplay.h"

#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace brittle {
namespace {

// Appends data to the single buffer as a new buffer view (4-byte aligned) and an accessor on it.
class Builder {
 public:
  explicit Builder(tinygltf::Model& model) : mModel(model) { mModel.buffers.emplace_back(); }

  int accessor(const void* data, size_t bytes, int componentType, int type, size_t count, int target,
               std::vector<double> minValues = {}, std::vector<double> maxValues = {}) {
    std::vector<unsigned char>& buffer = mModel.buffers[0].data;
    while (buffer.size() % 4 != 0) buffer.push_back(0);
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    if (target != 0) view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), p, p + bytes);
    mModel.bufferViews.push_back(view);
    tinygltf::Accessor a;
    a.bufferView = static_cast<int>(mModel.bufferViews.size() - 1);
    a.componentType = componentType;
    a.type = type;
    a.count = count;
    a.minValues = std::move(minValues);
    a.maxValues = std::move(maxValues);
    mModel.accessors.push_back(a);
    return static_cast<int>(mModel.accessors.size() - 1);
  }

  int floats(const std::vector<float>& v, int type, int components, int target, bool bounds) {
    std::vector<double> lo, hi;
    if (bounds) {
      lo.assign(static_cast<size_t>(components), std::numeric_limits<double>::infinity());
      hi.assign(static_cast<size_t>(components), -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < v.size(); ++i) {
        const size_t c = i % static_cast<size_t>(components);
        lo[c] = std::min(lo[c], static_cast<double>(v[i]));
        hi[c] = std::max(hi[c], static_cast<double>(v[i]));
      }
    }
    return accessor(v.data(), v.size() * sizeof(float), TINYGLTF_COMPONENT_TYPE_FLOAT, type, v.size() / static_cast<size_t>(components),
                    target, lo, hi);
  }

  // A triangle mesh (positions, indices) as a new glTF mesh; returns its index.
  int mesh(const std::string& name, const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
    tinygltf::Primitive prim;
    prim.attributes["POSITION"] = floats(positions, TINYGLTF_TYPE_VEC3, 3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
    prim.indices = accessor(indices.data(), indices.size() * sizeof(uint32_t), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                            TINYGLTF_TYPE_SCALAR, indices.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.material = 0;
    tinygltf::Mesh m;
    m.name = name;
    m.primitives.push_back(prim);
    mModel.meshes.push_back(m);
    return static_cast<int>(mModel.meshes.size() - 1);
  }

 private:
  tinygltf::Model& mModel;
};

void surfaceArrays(const TriangleMesh& s, std::vector<float>& positions, std::vector<uint32_t>& indices) {
  for (Eigen::Index v = 0; v < s.vertices.rows(); ++v)
    for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(s.vertices(v, k)));
  for (Eigen::Index f = 0; f < s.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<uint32_t>(s.faces(f, k)));
}

// A UV sphere (16 × 8) or a box, centred at the origin.
void impactorArrays(const RigidImpactor& imp, std::vector<float>& positions, std::vector<uint32_t>& indices) {
  if (imp.shape == ImpactorShape::Box) {
    for (int i = 0; i < 8; ++i)
      for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(((i >> k) & 1 ? 1.0 : -1.0) * imp.halfExtentsM[k]));
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads)
      for (uint32_t t : {q[0], q[1], q[2], q[0], q[2], q[3]}) indices.push_back(t);
    return;
  }
  const int slices = 16, stacks = 8;
  for (int i = 0; i <= stacks; ++i) {
    const double theta = std::numbers::pi * i / stacks;
    for (int j = 0; j < slices; ++j) {
      const double phi = 2.0 * std::numbers::pi * j / slices;
      positions.push_back(static_cast<float>(imp.radiusM * std::sin(theta) * std::cos(phi)));
      positions.push_back(static_cast<float>(imp.radiusM * std::sin(theta) * std::sin(phi)));
      positions.push_back(static_cast<float>(imp.radiusM * std::cos(theta)));
    }
  }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const uint32_t a = static_cast<uint32_t>(i * slices + j), b = static_cast<uint32_t>(i * slices + (j + 1) % slices);
      const uint32_t c = a + slices, d = b + slices;
      for (uint32_t t : {a, c, b, b, c, d}) indices.push_back(t);
    }
}

}  // namespace

Status writeGltfReplay(const PlayResult& result, const std::filesystem::path& path) {
  const int64_t samples = result.frames + 1;
  for (const BodyState& b : result.bodies) {
    const int64_t last = b.lastFrame < 0 ? result.frames : b.lastFrame;
    const int64_t expected = std::max<int64_t>(0, last - b.firstFrame + 1);
    if (static_cast<int64_t>(b.rotations.size()) != expected || b.translationsM.size() != b.rotations.size()) {
      return makeError(ErrorCode::InvalidArgument, "glTF replay: body '" + b.name + "' has " + std::to_string(b.rotations.size()) +
                                                       " pose samples, expected " + std::to_string(expected) +
                                                       " (play with recordTracks)");
    }
  }
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = std::string("brittle ") + BRITTLE_VERSION;
  Builder build(model);
  tinygltf::Material material;
  material.name = "body";
  material.pbrMetallicRoughness.baseColorFactor = {0.8, 0.85, 0.9, 1.0};
  material.doubleSided = true;
  model.materials.push_back(material);

  std::vector<float> times(static_cast<size_t>(samples));
  for (int64_t k = 0; k < samples; ++k) times[static_cast<size_t>(k)] = static_cast<float>(static_cast<double>(k) * result.timeStepS);
  const int timeAccessor = build.floats(times, TINYGLTF_TYPE_SCALAR, 1, 0, true);

  tinygltf::Scene scene;
  scene.name = result.scene;
  tinygltf::Node root;
  root.name = "z-up";
  // z up → y up: a rotation of −90° about x.
  root.rotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
  tinygltf::Animation animation;
  animation.name = result.scene;
  for (const BodyState& b : result.bodies) {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    if (b.kind == BodyKind::Impactor) impactorArrays(b.impactor, positions, indices);
    else surfaceArrays(b.surface, positions, indices);
    tinygltf::Node node;
    node.name = b.name;
    if (!indices.empty()) node.mesh = build.mesh(b.name, positions, indices);
    std::vector<float> translation, rotation, scale;
    Eigen::Quaterniond previous = Eigen::Quaterniond::Identity();
    for (int64_t k = 0; k < samples; ++k) {
      const int64_t last = b.lastFrame < 0 ? result.frames : b.lastFrame;
      const bool exists = k >= b.firstFrame && k <= last && !b.rotations.empty();
      const size_t i = b.rotations.empty() ? 0 : static_cast<size_t>(std::clamp<int64_t>(k - b.firstFrame, 0, static_cast<int64_t>(b.rotations.size()) - 1));
      const Eigen::Vector3d t = b.rotations.empty() ? Eigen::Vector3d::Zero() : b.translationsM[i];
      Eigen::Quaterniond q = b.rotations.empty() ? Eigen::Quaterniond::Identity() : b.rotations[i];
      if (k > 0 && q.dot(previous) < 0.0) q.coeffs() *= -1.0;  // q and −q: interpolate the short way
      previous = q;
      for (int c = 0; c < 3; ++c) translation.push_back(static_cast<float>(t[c]));
      for (double c : {q.x(), q.y(), q.z(), q.w()}) rotation.push_back(static_cast<float>(c));
      for (int c = 0; c < 3; ++c) scale.push_back(exists ? 1.0f : 0.0f);
    }
    model.nodes.push_back(node);
    const int nodeIndex = static_cast<int>(model.nodes.size() - 1);
    root.children.push_back(nodeIndex);
    auto channel = [&](const std::vector<float>& values, int type, int components, const char* pathName, const char* interpolation) {
      tinygltf::AnimationSampler sampler;
      sampler.input = timeAccessor;
      sampler.output = build.floats(values, type, components, 0, false);
      sampler.interpolation = interpolation;
      animation.samplers.push_back(sampler);
      tinygltf::AnimationChannel ch;
      ch.sampler = static_cast<int>(animation.samplers.size() - 1);
      ch.target_node = nodeIndex;
      ch.target_path = pathName;
      animation.channels.push_back(ch);
    };
    channel(translation, TINYGLTF_TYPE_VEC3, 3, "translation", "LINEAR");
    channel(rotation, TINYGLTF_TYPE_VEC4, 4, "rotation", "LINEAR");
    channel(scale, TINYGLTF_TYPE_VEC3, 3, "scale", "STEP");
  }
  model.nodes.push_back(root);
  scene.nodes.push_back(static_cast<int>(model.nodes.size() - 1));
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  model.animations.push_back(animation);
  model.buffers[0].name = "replay";

  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToFile(&model, path.string(), true, true, false, true)) {
    return makeError(ErrorCode::PackIoError, "cannot write glTF replay " + path.string());
  }
  return Ok{};
}

}  // namespace brittle
