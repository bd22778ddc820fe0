// drivetrain_replay's bag input (ReplayInput: checkBagIndex, rosbag::View, SequentialBagReader,
// the message layout check) on hostile bag files: whatever the bytes, construction either succeeds
// or refuses with InvalidInput naming the --bag path; reading never throws and ends at the bag's
// end or at damage inside the file; every message handed out fits in the file (no array longer
// than the bytes could hold); every string from the bag escapes to printable text. A crash, a
// sanitizer report or an allocation the size of a damaged length is a finding by itself.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "drivetrain_stiffness/core/validation.hpp"
#include "fuzz_target.hpp"
#include "bag/replay_input.hpp"

namespace drivetrain_stiffness::fuzz {
namespace {

/// One file per process, rewritten for every case (rosbag reads files, not memory).
const std::string& caseFile() {
  static const std::string path = [] {
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    return (dir / ("drivetrain_fuzz_bag_" + std::to_string(::getpid()) + ".bag")).string();
  }();
  static const struct Remove {
    ~Remove() { std::remove(path.c_str()); }
  } remove;
  return path;
}

void require(bool property, const std::string& what) {
  if (!property) throw FuzzFinding(what);
}

}  // namespace

CaseStats fuzzBag(const std::uint8_t* data, std::size_t size) {
  const std::string& path = caseFile();
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  CaseStats stats;
  std::unique_ptr<ReplayInput> input;
  try {
    input = std::make_unique<ReplayInput>(
        path, ReplayTopics{"torque", "preload", "joint_states", "vibration"});
  } catch (const InvalidInput& e) {
    require(std::string(e.what()).rfind("--bag = '" + path + "'", 0) == 0,
            std::string("refusal without the path: ") + e.what());
    stats.refuse(e.what());
    return stats;
  }
  try {
    for (const ReplayMessage& m : *input) {
      ++stats.accepted;
      std::size_t held = printableText(m.getTopic()).size() + printableText(m.getDataType()).size();
      if (const auto t = m.instantiate<geometry_msgs::WrenchStamped>())
        held += t->header.frame_id.size();
      if (const auto j = m.instantiate<sensor_msgs::JointState>()) {
        for (const std::string& name : j->name) held += 4 + printableText(name).size() / 4;
        held += 8 * (j->position.size() + j->velocity.size() + j->effort.size());
      }
      if (const auto p = m.instantiate<drivetrain_stiffness::Preload>())
        held += 36 * p->bearings.size();
      if (const auto v = m.instantiate<drivetrain_stiffness::VibrationBlock>()) {
        for (const std::string& name : v->channels) held += 4 + printableText(name).size() / 4;
        held += 4 * v->data.size();
      }
      require(held <= 4 * size + 64, "a message holds " + std::to_string(held) + " bytes from a " +
                                         std::to_string(size) + "-byte file");
    }
  } catch (const std::exception& e) {
    throw FuzzFinding(std::string("reading threw: ") + e.what());
  }
  if (const auto& damage = input->damage()) {
    require(damage->offset <= size, "damage at byte " + std::to_string(damage->offset) + " of a " +
                                        std::to_string(size) + "-byte file");
    stats.refuse(damage->what);
  }
  for (const BagTopic& t : input->topics()) {
    require(t.topic.size() <= size && t.messages <= size, "a topic larger than the file");
    printableText(t.topic);
  }
  return stats;
}

}  // namespace drivetrain_stiffness::fuzz
