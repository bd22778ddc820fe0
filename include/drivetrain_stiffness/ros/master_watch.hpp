// Notices that the ROS master restarted under a running node: docs/reliability.md "Faults".
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace drivetrain_stiffness {

class MasterWatch {
 public:
  /// Polls /run_id every `period` [s] from its own thread; calls `onRestart(old_run_id,
  /// new_run_id)` once, from that thread, when the master answers with another run id.
  MasterWatch(double period, std::function<void(const std::string&, const std::string&)> onRestart);
  ~MasterWatch();  ///< stops and joins the thread
  MasterWatch(const MasterWatch&) = delete;
  MasterWatch& operator=(const MasterWatch&) = delete;

 private:
  void run();
  double period_;
  std::function<void(const std::string&, const std::string&)> on_restart_;
  std::string run_id_;  ///< of the master this node registered with
  std::mutex mutex_;
  std::condition_variable stop_cv_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace drivetrain_stiffness
