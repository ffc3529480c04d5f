// SPDX-License-Identifier: Apache-2.0
#include "calibration_runner.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <thread>
#include <utility>

#include "calibration_output.hpp"
#include "swivel/robot_model_io.hpp"

namespace swivel::daemon {
namespace {

std::string progress_text(const CalibrationProgress& p) {
  char text[128];
  std::snprintf(text, sizeof text, "module %u/%u, run %u/%u: %s (%.0f %%)", p.module + 1,
                p.module_count, p.run + 1, p.runs_per_module, calibration_phase_name(p.phase),
                100.0 * p.fraction);
  return text;
}

}  // namespace

CalibrationRunner::CalibrationRunner(rt::ControlLoop& loop, PluginLoader& loader,
                                     RobotModel nominal, std::string model_path,
                                     PluginContext context, std::string plugin, Publish publish)
    : loop_(loop),
      loader_(loader),
      nominal_(std::move(nominal)),
      model_path_(std::move(model_path)),
      context_(std::move(context)),
      plugin_name_(std::move(plugin)),
      publish_(std::move(publish)) {
  context_.robot = &nominal_;
  status_.status = "idle";
  status_.text = "no calibration has run";
}

CalibrationRunner::~CalibrationRunner() {
  std::unique_lock lock(mutex_);
  if (loop_.calibration_in_flight()) {
    loop_.cancel_calibration();
    // The loop lets go at its next cycle; never destroy an instance it may still call.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    Calibration* back = loop_.take_finished_calibration();
    while (back == nullptr && loop_.running() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      back = loop_.take_finished_calibration();
    }
    if (back == nullptr) {
      std::fprintf(stderr, "swiveld: the loop did not hand the calibration back; leaking it\n");
      // Deliberately leaked: destroying it could free what the loop still runs.
      // NOLINTNEXTLINE(bugprone-unhandled-exception-at-new)
      (void)new PluginInstance<Calibration>(std::move(instance_));
      return;
    }
  }
  if (analysis_) analysis_->wait();
  instance_.reset();
}

void CalibrationRunner::set_status_locked(const std::string& status, const std::string& text) {
  status_.status = status;
  status_.text = text;
  if (status != "done") status_.modules.clear();
}

void CalibrationRunner::publish_locked() {
  if (publish_) publish_(status_);
}

std::string CalibrationRunner::start() {
  std::lock_guard lock(mutex_);
  if (instance_ || analysis_ || loop_.calibration_in_flight()) {
    return "a calibration is already running";
  }
  PluginInstance<Calibration> next;
  try {
    next = loader_.create<Calibration>(plugin_name_);
    next->configure(context_);
  } catch (const std::exception& e) {
    set_status_locked("failed", std::string("cannot start: ") + e.what());
    status_.progress = 0.0;
    publish_locked();
    return status_.text;
  }
  if (!loop_.start_calibration(next.get())) {
    set_status_locked("failed", "cannot start: the loop has a calibration in flight");
    publish_locked();
    return status_.text;
  }
  instance_ = std::move(next);
  set_status_locked("running", "started");
  status_.progress = 0.0;
  last_progress_s_ = loop_.now_s();
  publish_locked();
  return "";
}

void CalibrationRunner::cancel() {
  std::lock_guard lock(mutex_);
  if (!loop_.calibration_in_flight()) return;
  loop_.cancel_calibration();
  status_.text = "cancelling";
  publish_locked();
}

dds::CalibrationSample CalibrationRunner::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

std::string CalibrationRunner::calibrated_model_file() const {
  std::lock_guard lock(mutex_);
  return calibrated_file_;
}

std::string CalibrationRunner::apply_instructions() const {
  std::lock_guard lock(mutex_);
  if (calibrated_file_.empty()) return "no calibrated model to apply";
  return "set robot_model: " + calibrated_file_ + " and reload with the robot at rest";
}

void CalibrationRunner::handle_request(const std::string& argument) {
  if (argument == "start") {
    (void)start();  // publishes either way
  } else if (argument == "cancel") {
    cancel();
    std::lock_guard lock(mutex_);
    publish_locked();
  } else {
    std::lock_guard lock(mutex_);
    if (argument != "status" && !argument.empty()) {
      dds::CalibrationSample answer = status_;
      answer.text = "unknown calibrate argument '" + argument + "' (start | cancel | status)";
      if (publish_) publish_(answer);
      return;
    }
    publish_locked();
  }
}

void CalibrationRunner::poll() {
  std::lock_guard lock(mutex_);
  if (instance_ && !analysis_) {
    rt::CalibrationOutcome outcome = rt::CalibrationOutcome::kNone;
    Calibration* back = loop_.take_finished_calibration(&outcome);
    if (back == nullptr) {
      const double now_s = loop_.now_s();
      const CalibrationProgress p = instance_->progress();
      status_.progress = p.fraction;
      if (status_.text != "cancelling") status_.text = progress_text(p);
      if (now_s - last_progress_s_ >= progress_period_s_) {
        last_progress_s_ = now_s;
        publish_locked();
      }
      return;
    }
    // The loop let go: analyse off every real-time path, or report how it ended.
    const std::string error = instance_->last_error();  // static text of the library
    switch (outcome) {
      case rt::CalibrationOutcome::kFinished: {
        Calibration* calibration = instance_.get();
        analysis_ =
            std::async(std::launch::async, [calibration] { return calibration->analyse(); });
        status_.progress = 1.0;
        status_.text = "recorded every run; analysing";
        publish_locked();
        return;
      }
      case rt::CalibrationOutcome::kCancelled:
        set_status_locked("cancelled", "cancelled; the robot was stopped");
        break;
      case rt::CalibrationOutcome::kRefused:
        set_status_locked("failed", "refused: the loop is in safe stop (clear the fault first)");
        break;
      default: {
        const StateSnapshot s = loop_.latest();
        set_status_locked("failed", std::string("stopped by fault ") + fault_code_name(s.fault) +
                                        (error.empty() ? "" : ": " + error));
        break;
      }
    }
    instance_.reset();
    publish_locked();
    return;
  }
  if (analysis_ && analysis_->wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    finish_analysis_locked();
  }
}

void CalibrationRunner::finish_analysis_locked() {
  CalibrationReport report;
  try {
    report = analysis_->get();
  } catch (const std::exception& e) {
    report.ok = false;
    report.reason = std::string("analysis failed: ") + e.what();
  }
  analysis_.reset();
  instance_.reset();
  if (!report.ok) {
    set_status_locked("failed", "refused: " + report.reason);
    publish_locked();
    return;
  }
  const SavedModel saved = save_calibrated_model(report.model, model_path_, std::time(nullptr));
  fill_modules_locked(report);
  if (saved.path.empty()) {
    // Not lost: the parameters stay in this status (swivelctl echo calibration) and the
    // whole model goes to the log, from where it can be saved by hand.
    spdlog::error("calibration: the calibrated model could not be written; it follows:\n{}",
                  robot_model_to_yaml(report.model));
    set_status_locked("failed", "calibrated, but the model could not be written (" + saved.error +
                                    "); its parameters are in this status and the whole model "
                                    "in swiveld's log. Give the service a writable "
                                    "StateDirectory= (the shipped unit has /var/lib/swivel) or "
                                    "make one of those folders writable");
    publish_locked();
    return;
  }
  calibrated_file_ = saved.path;
  set_status_locked("done", "calibrated model written to " + calibrated_file_ +
                                "; to apply it, set robot_model: " + calibrated_file_ +
                                " and reload with the robot at rest");
  status_.progress = 1.0;
  publish_locked();
}

void CalibrationRunner::fill_modules_locked(const CalibrationReport& report) {
  status_.modules.clear();
  for (std::size_t i = 0; i < report.model.modules.size() && i < kMaxModules; ++i) {
    const SwpcModuleParams& m = report.model.modules[i];
    const SwpcModuleUncertainty u =
        i < report.uncertainty.size() ? report.uncertainty[i] : SwpcModuleUncertainty{};
    status_.modules.push_back({m.x_m, m.y_m, m.steering_offset_rad, m.caster_offset_m,
                               m.wheel_radius_m, u.x_m, u.y_m, u.steering_offset_rad,
                               u.caster_offset_m, u.wheel_radius_m});
  }
}

}  // namespace swivel::daemon
