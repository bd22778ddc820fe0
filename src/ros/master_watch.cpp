#include "drivetrain_stiffness/ros/master_watch.hpp"

#include <chrono>

#include <ros/master.h>
#include <ros/param.h>

namespace drivetrain_stiffness {
namespace {

/// The master's /run_id (set by roslaunch/roscore at every start), or "" when it does not answer.
/// ros::param::get asks the master every time (getCached would not), and does not wait for it.
std::string masterRunId() {
  std::string id;
  if (!ros::master::check() || !ros::param::get("/run_id", id)) return "";
  return id;
}

}  // namespace

MasterWatch::MasterWatch(double period,
                         std::function<void(const std::string&, const std::string&)> onRestart)
    : period_(period),
      on_restart_(std::move(onRestart)),
      run_id_(masterRunId()),
      thread_([this] { run(); }) {}

MasterWatch::~MasterWatch() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  stop_cv_.notify_all();
  thread_.join();
}

void MasterWatch::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (
      !stop_cv_.wait_for(lock, std::chrono::duration<double>(period_), [this] { return stop_; })) {
    lock.unlock();
    const std::string id = masterRunId();
    lock.lock();
    if (id.empty()) continue;  // the master is away: wait for the one that comes back
    if (run_id_.empty()) {
      run_id_ = id;  // started without /run_id (a bare rosmaster): the first answer is the baseline
    } else if (id != run_id_) {
      const std::string old = run_id_;
      run_id_ = id;
      lock.unlock();
      on_restart_(old, id);
      lock.lock();
    }
  }
}

}  // namespace drivetrain_stiffness
