// OrderedWorker: one background thread that consumes items in the order they were submitted, so
// output written from it is the same bytes as if written inline (drivetrain_replay's bit-identity).
// The replay uses it to move output formatting, compression and file writes off the analysis
// thread (BagWriter chunks, CSV blocks). The queue is bounded, so a slow disk slows the producer
// instead of growing memory. An exception in the consumer is kept and rethrown to the producer at
// its next submit() or at finish(); later items are then dropped, not written out of order.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace drivetrain_stiffness {

template <typename Item>
class OrderedWorker {
 public:
  explicit OrderedWorker(std::function<void(Item&)> consume, std::size_t max_queued = 4)
      : consume_(std::move(consume)), max_queued_(max_queued), thread_([this] { run(); }) {}
  ~OrderedWorker() {
    try {
      finish();
    } catch (...) {  // the owner's close() reports errors; a destructor must not throw
    }
  }
  OrderedWorker(const OrderedWorker&) = delete;
  OrderedWorker& operator=(const OrderedWorker&) = delete;

  void submit(Item item) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return queue_.size() < max_queued_ || error_; });
      if (error_) std::rethrow_exception(error_);
      queue_.push_back(std::move(item));
    }
    changed_.notify_all();
  }

  /// The owners' close sequence: `flush` submits what the owner still holds, then finish(). Returns
  /// the first error of the two (null if none) instead of throwing, so the owner can still close
  /// its file before rethrowing.
  template <typename Flush>
  std::exception_ptr flushAndFinish(Flush flush) noexcept {
    std::exception_ptr error;
    try {
      flush();
    } catch (...) {
      error = std::current_exception();
    }
    try {
      finish();
    } catch (...) {
      if (!error) error = std::current_exception();
    }
    return error;
  }

  /// Consumes what is queued, stops the thread, and rethrows the consumer's first error.
  void finish() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finishing_ = true;
    }
    changed_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  }

 private:
  void run() {
    for (;;) {
      Item item;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [this] { return !queue_.empty() || finishing_; });
        if (queue_.empty()) return;
        item = std::move(queue_.front());
        queue_.pop_front();
      }
      changed_.notify_all();
      try {
        if (!failed_) consume_(item);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = std::current_exception();
        failed_ = true;
      }
      changed_.notify_all();
    }
  }

  std::function<void(Item&)> consume_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Item> queue_;
  bool finishing_ = false;
  bool failed_ = false;  ///< consumer thread only
  std::exception_ptr error_;
  std::thread thread_;  ///< last: starts after every member above exists
};

}  // namespace drivetrain_stiffness
