// Notices that the ROS master restarted under a running node. roscpp registers publishers,
// subscribers and services once, at creation, and never again: after a new master comes up (same
// URI, new /run_id) the node still runs but nobody can find it. The watch polls /run_id from its
// own thread (an XML-RPC call, kept off the callback thread that serves the inputs) and calls
// `onRestart` once, from that thread, when the master answers with another run id.
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
  /// `period` [s] between polls; `onRestart(old_run_id, new_run_id)`.
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
