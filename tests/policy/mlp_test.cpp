// MLP weight format: round trip, clear errors for truncated / corrupt / wrong-shape files, history
#include "actionshift/core/error.hpp"
#include "actionshift/core/hash.hpp"
#include "actionshift/policy/mlp.hpp"
#include "actionshift/policy/registry.hpp"
#include "actionshift/sim/task.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

using namespace actionshift;
using ::testing::HasSubstr;

namespace {

policy::MlpWeights small_net(sim::TaskId task, int history = 0) {
  auto w = policy::MlpWeights::init(task, history, {16, 8}, 11);
  w.input_mean.setConstant(0.1f);
  w.input_std.setConstant(2.0f);
  return w;
}

template <class F>
void expect_input_error(F f, const std::string& part) {
  EXPECT_THAT(f, ::testing::ThrowsMessage<InputError>(HasSubstr(part)));
}

TEST(MlpFormat, RoundTripKeepsTheFunction) {
  const auto w = small_net(sim::TaskId::kPushCube);
  const std::string bytes = policy::serialize_mlp(w);
  const auto back = policy::parse_mlp(bytes, "net.asmlp");
  EXPECT_EQ(back.layers, w.layers);
  const Eigen::VectorXf x = Eigen::VectorXf::LinSpaced(35, -1.0f, 1.0f);
  EXPECT_TRUE(policy::mlp_forward(w, x).isApprox(policy::mlp_forward(back, x)));
  EXPECT_EQ(policy::serialize_mlp(back), bytes);
}

TEST(MlpFormat, TruncatedCorruptAndWrongShapeAreOneLineErrors) {
  const std::string bytes = policy::serialize_mlp(small_net(sim::TaskId::kPickCube));
  expect_input_error([&] { policy::parse_mlp(bytes.substr(0, bytes.size() - 5), "w.asmlp"); }, "w.asmlp: payload: truncated");
  expect_input_error([&] { policy::parse_mlp(bytes.substr(0, 10), "w.asmlp"); }, "truncated");
  expect_input_error([&] { policy::parse_mlp(bytes + "xx", "w.asmlp"); }, "trailing bytes");
  std::string corrupt = bytes;
  corrupt[corrupt.size() - 3] ^= 0x5a;
  expect_input_error([&] { policy::parse_mlp(corrupt, "w.asmlp"); }, "checksum mismatch");
  std::string magic = bytes;
  magic[0] = 'X';
  expect_input_error([&] { policy::parse_mlp(magic, "w.asmlp"); }, "bad magic");
  // a pick_cube network relabelled as push_cube: the input size no longer matches the task
  std::string relabel = bytes;
  const auto at = relabel.find("\"task\":\"pick_cube\"");
  ASSERT_NE(at, std::string::npos);
  relabel.replace(at, 18, "\"task\":\"push_cube\"");
  expect_input_error([&] { policy::parse_mlp(relabel, "w.asmlp"); }, "input size 42 does not match task push_cube (expected 35)");
  expect_input_error([] { policy::load_mlp("/nonexistent/w.asmlp"); }, "/nonexistent/w.asmlp: no such file");
}

// the header's text replaced (its length field rewritten), as a hostile writer would
std::string with_header_edit(const std::string& bytes, const std::string& from, const std::string& to) {
  std::uint32_t hlen = 0;
  std::memcpy(&hlen, bytes.data() + 12, 4);
  std::string header = bytes.substr(16, hlen);
  const auto at = header.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) header.replace(at, from.size(), to);
  const auto n = static_cast<std::uint32_t>(header.size());
  std::string out = bytes.substr(0, 12);
  out.append(reinterpret_cast<const char*>(&n), 4);
  return out + header + bytes.substr(16 + hlen);
}

TEST(MlpFormat, HostileHeaderNumbersAreOneLineErrors) {
  const std::string bytes = policy::serialize_mlp(small_net(sim::TaskId::kPickCube));
  // 1e30 does not fit an int: an error, not an undefined float-to-int conversion
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"history\":0", "\"history\":1e30"), "w.asmlp"); },
                     "w.asmlp: header.history: expected an integer in the range of int (got 1e+30)");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"history\":0", "\"history\":2.5"), "w.asmlp"); },
                     "header.history: expected an integer");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"history\":0", "\"history\":1e999"), "w.asmlp"); },
                     "w.asmlp: header.history: number out of range");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"layers\":[", "\"layers\":[4294967338,"), "w.asmlp"); },
                     "header.layers: expected an integer");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"history\":0", "\"history\":" + std::string(100, '[') + std::string(100, ']')), "w.asmlp"); },
                     "nested deeper than 64 levels");
  expect_input_error([] { policy::load_mlp(std::filesystem::temp_directory_path().string()); }, "is a directory");
}

TEST(MlpFormat, DescriptiveHeaderFieldsMustDescribeTheFile) {
  // these loaded with a correct payload checksum before every field was compared with the file
  const std::string bytes = policy::serialize_mlp(small_net(sim::TaskId::kPickCube));
  EXPECT_NO_THROW(policy::parse_mlp(bytes, "w.asmlp"));
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"activation\":\"tanh\"", "\"activation\":\"relu\""), "w.asmlp"); },
                     "w.asmlp: header.activation: expected \"tanh\" (got \"relu\")");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"output\":\"clip[-1,1]\"", "\"output\":\"none\""), "w.asmlp"); },
                     "header.output: expected");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"parameters\":", "\"parameters\":1,\"x\":"), "w.asmlp"); },
                     "header.parameters: expected");
  expect_input_error([&] { policy::parse_mlp(with_header_edit(bytes, "\"payload_floats\":", "\"payload_floats\":-1,\"y\":"), "w.asmlp"); },
                     "header.payload_floats: expected");
  expect_input_error([&] { policy::load_mlp("/dev/zero"); }, "/dev/zero: not a regular file");
}

TEST(MlpPolicy, HistoryHoldsTheLastFourActionsMostRecentFirst) {
  // a network whose output is independent of the history, so the history is just its own outputs
  auto w = std::make_shared<policy::MlpWeights>(small_net(sim::TaskId::kPushCube, policy::kHistoryLength));
  EXPECT_EQ(w->input_dim(), 35 + 28);
  policy::MlpPolicy p(w, "0");
  p.reset();
  Eigen::VectorXd obs = Eigen::VectorXd::Zero(35);
  std::vector<Action> out;
  for (int t = 0; t < 6; ++t) {
    obs(0) = 0.1 * t;
    out.push_back(p.act(obs));
  }
  // replaying with a plain forward pass and a hand-built history reproduces every output
  for (int t = 0; t < 6; ++t) {
    Eigen::VectorXf x = Eigen::VectorXf::Zero(63);
    x(0) = static_cast<float>(0.1 * t);
    for (int j = 0; j < 4 && t - 1 - j >= 0; ++j) x.segment(35 + 7 * j, 7) = out[static_cast<std::size_t>(t - 1 - j)].cast<float>();
    EXPECT_TRUE(policy::mlp_forward(*w, x).isApprox(out[static_cast<std::size_t>(t)], 1e-6)) << t;
  }
  p.reset();
  obs(0) = 0.0;
  EXPECT_TRUE(p.act(obs).isApprox(out[0]));
  EXPECT_EQ(p.name(), "mlp-delay-aware");
}

TEST(MlpBackbones, EveryCommittedWeightFileIsListedWithItsChecksumAndLoadsAsItsBackbone) {
  std::ifstream sums(ACTIONSHIFT_SOURCE_DIR "/configs/backbones/SHA256SUMS");
  std::map<std::string, std::string> listed;
  for (std::string sha, file; sums >> sha >> file;) listed[file] = sha;
  int files = 0;
  // the backbones themselves (MLP and PPO actors, .asmlp; Diffusion Policies, .asdp), under stages/ the
  // files a committed backbone was warm-started from (`train ppo --init-from`; named
  // <task>.<backbone>.<env steps>.asmlp, kept so its command re-runs), and under replicas/ the
  // independently trained replicas (<task>.ppo.seed<S>.asmlp, `mlp:<path>`)
  const std::filesystem::path root = ACTIONSHIFT_SOURCE_DIR "/configs/backbones";
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    const std::string name = entry.path().filename().string();
    const bool dp = name.ends_with(".asdp");  // an adopted Diffusion Policy, <task>.dp.asdp (backbone `dp`)
    if (!name.ends_with(".asmlp") && !dp) continue;
    ++files;
    const std::string rel = std::filesystem::relative(entry.path(), root).generic_string();
    std::ifstream f(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(listed[rel], sha256_hex(bytes)) << rel << " vs SHA256SUMS";
    const std::string stem = name.substr(0, name.size() - (dp ? 5 : 6));
    const auto dot = stem.find('.');
    ASSERT_NE(dot, std::string::npos) << name;
    const sim::TaskId task = sim::parse_task(stem.substr(0, dot));
    if (dp) {
      ASSERT_EQ(rel, std::string(sim::task_name(task)) + ".dp.asdp") << "a Diffusion Policy file is named <task>.dp.asdp";
    }
    if (rel != name) {  // a stage or a replica: loads as a weight file of its task
      ASSERT_TRUE(rel.rfind("stages/", 0) == 0 || rel.rfind("replicas/", 0) == 0) << rel;
      EXPECT_EQ(policy::MlpPolicy::from_file(entry.path().string())->task(), task) << rel;
      continue;
    }
    // <task>.<backbone>.asmlp loads through the registry as that backbone, for that task
    policy::RegistryOptions ro;
    ro.backbones_dir = root.string();
    auto p = policy::make_policy(stem.substr(dot + 1), task, ro);
    EXPECT_EQ(p->task(), task) << name;
    EXPECT_EQ(p->name(), stem.substr(dot + 1)) << name;
    EXPECT_EQ(p->sha256(), sha256_hex(bytes)) << name;
  }
  EXPECT_EQ(files, static_cast<int>(listed.size()));
}

TEST(MlpBackbones, CommittedWeightsHaveTheirDocumentedLayersAndChecksums) {
  // docs/backbones.md: 2 x 512 tanh for pick_cube (chosen on a pilot seed), 2 x 256 for the others
  std::ifstream sums(ACTIONSHIFT_SOURCE_DIR "/configs/backbones/SHA256SUMS");
  std::map<std::string, std::string> listed;
  for (std::string sha, file; sums >> sha >> file;) listed[file] = sha;
  for (sim::TaskId task : {sim::TaskId::kPickCube, sim::TaskId::kPushCube, sim::TaskId::kPullCube, sim::TaskId::kStackCube}) {
    const std::string path = policy::mlp_weights_path("mlp", task, ACTIONSHIFT_SOURCE_DIR "/configs/backbones");
    auto p = policy::MlpPolicy::from_file(path);
    EXPECT_EQ(p->task(), task);
    const std::size_t in = sim::observation_layout(task).size();
    const std::size_t h = task == sim::TaskId::kPickCube ? 512 : 256;
    EXPECT_EQ(p->weights().parameter_count(), in * h + h + h * h + h + h * 7 + 7) << path;
    EXPECT_LT(std::filesystem::file_size(path), 2u * 1024 * 1024);
    std::ifstream f(path, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_EQ(p->sha256(), sha256_hex(bytes));
    EXPECT_EQ(listed[std::filesystem::path(path).filename().string()], p->sha256()) << path << " vs SHA256SUMS";
  }
  expect_input_error(
      [] {
        policy::make_policy("mlp:" ACTIONSHIFT_SOURCE_DIR "/configs/backbones/pick_cube.mlp.asmlp", sim::TaskId::kPushCube);
      },
      "weights are for pick_cube, not push_cube");
}

}  // namespace
