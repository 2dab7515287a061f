#include "parallax/sfm/image_cluster.h"

#include <algorithm>
#include <map>
#include <ostream>
#include <set>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {

void WriteImageCluster(const ImageCluster& cluster, const std::filesystem::path& path) {
  WriteFileAtomically(path, [&](std::ostream& stream) {
    stream << "# Parallax image cluster: " << cluster.image_names.size() << " images, "
           << cluster.pairs.size() << " pairs\n";
    for (const std::string& name : cluster.image_names) stream << "image " << name << "\n";
    for (const auto& [name1, name2] : cluster.pairs)
      stream << "pair " << name1 << "\t" << name2 << "\n";
  });
}

ImageCluster ReadImageCluster(const std::filesystem::path& path) {
  ImageCluster cluster;
  std::set<std::string> names;
  const std::vector<std::string> lines = SplitLines(ReadFileToString(path));
  for (size_t index = 0; index < lines.size(); ++index) {
    const std::string line = Trim(lines[index]);
    const auto fail = [&](const std::string& problem) {
      throw InputError(path.string() + ": line " + std::to_string(index + 1) + ": " + problem);
    };
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.find(' ');
    const std::string keyword = line.substr(0, space);
    const std::string rest = space == std::string::npos ? "" : Trim(line.substr(space + 1));
    if (keyword == "image") {
      if (rest.empty()) fail("image without a name");
      if (!names.insert(rest).second) fail("image '" + rest + "' listed twice");
      cluster.image_names.push_back(rest);
    } else if (keyword == "pair") {
      const size_t tab = rest.find('\t');
      if (tab == std::string::npos) fail("pair needs two image names separated by a tab");
      const std::string name1 = Trim(rest.substr(0, tab));
      const std::string name2 = Trim(rest.substr(tab + 1));
      if (name1.empty() || name2.empty() || name1 == name2)
        fail("pair needs two different image names");
      cluster.pairs.emplace_back(name1, name2);
    } else {
      fail("expected 'image NAME' or 'pair NAME1<TAB>NAME2', got '" + line + "'");
    }
  }
  if (cluster.image_names.empty()) throw InputError(path.string() + ": no images in the cluster");
  for (const auto& [name1, name2] : cluster.pairs) {
    for (const std::string& name : {name1, name2}) {
      if (!names.count(name)) {
        throw InputError(path.string() + ": pair image '" + name +
                         "' is not among the cluster's images");
      }
    }
  }
  return cluster;
}

ImageCluster MakeImageCluster(const MapperInput& input, const std::vector<image_t>& image_ids) {
  ImageCluster cluster;
  const std::set<image_t> members(image_ids.begin(), image_ids.end());
  for (const image_t image_id : members)
    cluster.image_names.push_back(input.images.at(image_id).name);
  for (const auto& [pair_id, geometry] : input.two_view_geometries) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    if (members.count(image_id1) && members.count(image_id2)) {
      cluster.pairs.emplace_back(input.images.at(image_id1).name, input.images.at(image_id2).name);
    }
  }
  return cluster;
}

MapperInput ClusterMapperInput(const MapperInput& input, const ImageCluster& cluster,
                               const std::string& source) {
  std::map<std::string, image_t> id_of_name;
  for (const auto& [image_id, image] : input.images) id_of_name.emplace(image.name, image_id);
  const auto find_id = [&](const std::string& name) {
    const auto it = id_of_name.find(name);
    if (it == id_of_name.end())
      throw InputError(source + ": image '" + name + "' is not in the database");
    return it->second;
  };
  MapperInput part;
  for (const std::string& name : cluster.image_names) {
    const image_t image_id = find_id(name);
    const Image& image = input.images.at(image_id);
    part.images.emplace(image_id, image);
    part.cameras.emplace(image.camera_id, input.cameras.at(image.camera_id));
  }
  for (const auto& [name1, name2] : cluster.pairs) {
    const image_t image_id1 = find_id(name1);
    const image_t image_id2 = find_id(name2);
    const image_pair_t pair_id = ImagePairToPairId(image_id1, image_id2);
    const auto it = input.two_view_geometries.find(pair_id);
    if (it == input.two_view_geometries.end()) {
      throw InputError(source + ": pair '" + name1 + "' - '" + name2 +
                       "' has no verified geometry in the database");
    }
    part.two_view_geometries.emplace(pair_id, it->second);
  }
  MapperInputOptions keep_all;
  keep_all.min_num_matches = 0;
  FinalizeMapperInput(keep_all, &part);
  return part;
}

}  // namespace parallax
