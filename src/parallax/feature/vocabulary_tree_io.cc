// The vocabulary tree's file format (VocabularyTree::Write, Read): a header, one record per
// node with its centroid, and a digest of the whole.

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "parallax/feature/vocabulary_tree.h"
#include "parallax/util/byte_order.h"
#include "parallax/util/check.h"
#include "parallax/util/content_hash.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

constexpr int kLanes = VocabularyTree::kPanelLanes;
constexpr uint32_t kInnerNode = std::numeric_limits<uint32_t>::max();
constexpr char kMagic[8] = {'P', 'L', 'X', 'V', 'O', 'C', 'A', 'B'};
constexpr uint32_t kFormatVersion = 1;
constexpr size_t kHeaderBytes = 8 + 5 * 4;
constexpr size_t kDigestBytes = 32;

void AppendU32(std::string* bytes, uint32_t value) {
  const char le[4] = {char(value), char(value >> 8), char(value >> 16), char(value >> 24)};
  bytes->append(le, 4);
}

uint32_t LoadU32(const std::string& bytes, size_t offset) {
  return LittleEndian32(reinterpret_cast<const uint8_t*>(bytes.data() + offset));
}

}  // namespace

void VocabularyTree::Write(std::ostream& stream) const {
  PARALLAX_CHECK(!nodes_.empty());
  std::string bytes(kMagic, sizeof(kMagic));
  for (const int value :
       {static_cast<int>(kFormatVersion), dimension_, branching_, NumNodes(), num_words_}) {
    AppendU32(&bytes, static_cast<uint32_t>(value));
  }
  // Each centroid lives in its parent's panel: lane c of group g.
  std::vector<const float*> centroid_panel(nodes_.size(), nullptr);
  std::vector<int> centroid_lane(nodes_.size(), 0);
  const size_t panel_size = static_cast<size_t>(num_groups_) * dimension_ * kLanes;
  for (const Node& node : nodes_) {
    for (uint32_t c = 0; c < node.num_children; ++c) {
      centroid_panel[node.first_child + c] =
          panels_.data() + node.word * panel_size +
          (c / kLanes) * static_cast<size_t>(dimension_) * kLanes;
      centroid_lane[node.first_child + c] = c % kLanes;
    }
  }
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& node = nodes_[i];
    AppendU32(&bytes, node.first_child);
    AppendU32(&bytes, node.num_children);
    AppendU32(&bytes, node.num_children == 0 ? node.word : kInnerNode);
    for (int k = 0; k < dimension_; ++k) {
      const float value =
          centroid_panel[i] ? centroid_panel[i][k * kLanes + centroid_lane[i]] : 0.0f;
      AppendU32(&bytes, std::bit_cast<uint32_t>(value));
    }
  }
  bytes += HashBytes(bytes);
  stream.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void VocabularyTree::Write(const std::filesystem::path& path) const {
  WriteFileAtomically(
      path, [&](std::ostream& stream) { Write(stream); }, /*binary=*/true);
}

VocabularyTree VocabularyTree::Read(const std::filesystem::path& path, int expected_dimension) {
  return FromBytes(ReadFileToString(path), path.string(), expected_dimension);
}

VocabularyTree VocabularyTree::Read(std::istream& stream, const std::string& name,
                                    int expected_dimension) {
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  return FromBytes(buffer.str(), name, expected_dimension);
}

VocabularyTree VocabularyTree::FromBytes(const std::string& bytes, const std::string& name,
                                         int expected_dimension) {
  auto fail = [&](const std::string& problem) { throw InputError(name + ": " + problem); };
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    fail("not a vocabulary tree (no PLXVOCAB magic)");
  }
  if (bytes.size() < kHeaderBytes) fail("truncated vocabulary tree header");
  const uint32_t version = LoadU32(bytes, 8);
  if (version != kFormatVersion)
    fail("unsupported vocabulary tree format version " + std::to_string(version));
  const uint32_t dimension = LoadU32(bytes, 12), branching = LoadU32(bytes, 16);
  const uint32_t num_nodes = LoadU32(bytes, 20), num_words = LoadU32(bytes, 24);
  if (dimension < 1 || dimension > 65536 || branching < 2 || branching > 4096 || num_nodes < 1 ||
      num_words < 1 || num_words > num_nodes) {
    fail("inconsistent vocabulary tree header");
  }
  const size_t record_bytes = 12 + 4 * static_cast<size_t>(dimension);
  const size_t expected_bytes = kHeaderBytes + num_nodes * record_bytes + kDigestBytes;
  if (bytes.size() < expected_bytes) {
    fail("truncated vocabulary tree (" + std::to_string(bytes.size()) + " bytes, expected " +
         std::to_string(expected_bytes) + ")");
  }
  if (bytes.size() > expected_bytes) {
    fail(std::to_string(bytes.size() - expected_bytes) +
         " trailing bytes after the vocabulary tree");
  }
  const std::string_view body(bytes.data(), expected_bytes - kDigestBytes);
  if (HashBytes(body) != bytes.substr(body.size()))
    fail("vocabulary tree checksum mismatch (corrupt file)");
  if (expected_dimension > 0 && dimension != static_cast<uint32_t>(expected_dimension)) {
    fail("vocabulary tree for " + std::to_string(dimension) + "-D descriptors, expected " +
         std::to_string(expected_dimension) + "-D");
  }

  VocabularyTree tree;
  tree.dimension_ = static_cast<int>(dimension);
  tree.branching_ = static_cast<int>(branching);
  tree.num_groups_ = (tree.branching_ + kLanes - 1) / kLanes;
  tree.nodes_.resize(num_nodes);
  std::vector<float> centroids(static_cast<size_t>(num_nodes) * dimension);
  std::vector<uint8_t> has_parent(num_nodes, 0);
  std::vector<uint8_t> word_seen(num_words, 0);
  uint32_t num_leaves = 0;
  for (uint32_t i = 0; i < num_nodes; ++i) {
    const size_t offset = kHeaderBytes + i * record_bytes;
    Node& node = tree.nodes_[i];
    node.first_child = LoadU32(bytes, offset);
    node.num_children = LoadU32(bytes, offset + 4);
    const uint32_t word = LoadU32(bytes, offset + 8);
    const std::string what = "vocabulary tree node " + std::to_string(i);
    if (node.num_children == 0) {
      if (word >= num_words || word_seen[word])
        fail(what + ": bad or repeated word " + std::to_string(word));
      word_seen[word] = 1;
      node.word = word;
      ++num_leaves;
    } else {
      // Children numbered after their parent and each with one parent: the nodes form a tree.
      if (word != kInnerNode || node.num_children > branching || node.first_child <= i ||
          uint64_t{node.first_child} + node.num_children > num_nodes) {
        fail(what + ": children [" + std::to_string(node.first_child) + ", +" +
             std::to_string(node.num_children) + ") out of range");
      }
      for (uint32_t c = node.first_child; c < node.first_child + node.num_children; ++c) {
        if (has_parent[c]++) fail("vocabulary tree node " + std::to_string(c) + " has two parents");
      }
    }
    for (uint32_t k = 0; k < dimension; ++k) {
      const float value = std::bit_cast<float>(LoadU32(bytes, offset + 12 + 4 * k));
      if (!std::isfinite(value)) fail(what + ": centroid not finite");
      centroids[static_cast<size_t>(i) * dimension + k] = value;
    }
  }
  // Every node but the root has a parent; with distinct words below num_words, all are used.
  if (std::count(has_parent.begin() + 1, has_parent.end(), 0) > 0 || num_leaves != num_words) {
    fail("vocabulary tree nodes unreachable or words missing");
  }
  tree.Build(centroids);
  return tree;
}

}  // namespace parallax
