// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/topics.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <string_view>
#include <vector>

#include "swivel/shipped_config.hpp"

namespace swivel::dds {

dds_return_t check(dds_return_t rc, const char* what) {
  if (rc < 0) {
    throw DdsError(std::string(what) + ": " + dds_strretcode(rc));
  }
  return rc;
}

namespace {

QosPtr make_qos(int depth, dds_reliability_kind_t reliability, int max_depth = 100) {
  QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(), reliability, DDS_MSECS(100));
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, std::clamp(depth, 1, max_depth));
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  return qos;
}

// Cyclone DDS's log (errors and warnings; Cyclone writes them to stderr itself otherwise)
// goes through cyclone_log_sink: the same lines on stderr, except that handshake failures
// are rate-limited (a peer with foreign or no credentials retries about twice a second, for
// as long as it runs), and the errors this thread logs while a CycloneErrors is alive are
// kept for the message of the exception that follows.
thread_local std::string* tl_cyclone_errors = nullptr;

// At most one handshake-failure line per interval; the next one says how many were left out.
constexpr auto kHandshakeLogInterval = std::chrono::seconds(10);

bool is_handshake_failure(std::string_view message) {
  return message.find("andshake") != std::string_view::npos &&
         message.find("failed") != std::string_view::npos;
}

void cyclone_log_sink(void* /*userdata*/, const dds_log_data_t* data) {
  const std::string_view message(data->message, data->size);  // without the newline
  if (tl_cyclone_errors != nullptr && (data->priority & (DDS_LC_ERROR | DDS_LC_FATAL)) != 0) {
    if (!tl_cyclone_errors->empty()) tl_cyclone_errors->append("; ");
    tl_cyclone_errors->append(message);
  }
  std::string note;
  if (is_handshake_failure(message)) {
    static std::mutex mutex;
    static std::chrono::steady_clock::time_point last_logged;
    static bool logged_any = false;
    static unsigned left_out = 0;
    const auto now = std::chrono::steady_clock::now();
    const std::scoped_lock lock(mutex);
    if (logged_any && now - last_logged < kHandshakeLogInterval) {
      ++left_out;
      return;
    }
    if (left_out > 0) {
      note = " (" + std::to_string(left_out) + " more handshake failures since the last one " +
             "logged, not logged: at most one every " +
             std::to_string(kHandshakeLogInterval.count()) + " s)";
    }
    logged_any = true;
    last_logged = now;
    left_out = 0;
  }
  // Cyclone's header (time, domain, thread) precedes the message in the same buffer.
  std::fwrite(data->message - data->hdrsize, 1, data->hdrsize + data->size, stderr);
  std::fputs(note.c_str(), stderr);
  std::fputc('\n', stderr);
  std::fflush(stderr);
}

void install_cyclone_log_sink() {
  static std::once_flag once;
  std::call_once(once, [] { dds_set_log_sink(cyclone_log_sink, nullptr); });
}

// The errors Cyclone logs on this thread while alive: the cause behind a bare return code.
class CycloneErrors {
 public:
  CycloneErrors() : previous_(tl_cyclone_errors) { tl_cyclone_errors = &text_; }
  ~CycloneErrors() { tl_cyclone_errors = previous_; }
  CycloneErrors(const CycloneErrors&) = delete;
  CycloneErrors& operator=(const CycloneErrors&) = delete;
  CycloneErrors(CycloneErrors&&) = delete;
  CycloneErrors& operator=(CycloneErrors&&) = delete;

  /// "" or "; Cyclone DDS: <the errors, '; '-separated>".
  [[nodiscard]] std::string suffix() const {
    return text_.empty() ? std::string() : "; Cyclone DDS: " + text_;
  }

 private:
  std::string text_;
  std::string* previous_;
};

// The Cyclone configuration file in effect when it is one file: CYCLONEDDS_URI when set (it
// overrides dds.config, see resolve_config), else the configuration's dds.config; "" when
// that is not a single file:// URI (XML text, a list) or neither is set.
std::string config_file(const std::string& config_uri) {
  std::string uri = config_uri;
  const char* env = std::getenv("CYCLONEDDS_URI");
  if (env != nullptr && *env != '\0') uri = env;
  constexpr std::string_view kScheme = "file://";
  if (!uri.starts_with(kScheme) || uri.find(',') != std::string::npos) return {};
  return uri.substr(kScheme.size());
}

// "" when this process may read `path`, else "<path> (<reason>)".
std::string unreadable(const std::string& path) {
  if (::access(path.c_str(), R_OK) == 0) return {};
  const int error = errno;
  return path + " (" + std::strerror(error) + ", uid " + std::to_string(::geteuid()) + ")";
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The file: paths in the element texts of a Cyclone configuration: with DDS Security, the
// certificates, the key, the governance and the permissions.
std::vector<std::string> referenced_files(const std::string& xml) {
  static const std::regex file_reference(R"(>\s*file:([^<\s]+)\s*<)");
  std::vector<std::string> files;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), file_reference);
       it != std::sregex_iterator(); ++it) {
    files.push_back((*it)[1].str());
  }
  return files;
}

// Why a participant could not be created, beyond Cyclone's return code: a configuration or
// DDS Security file this process cannot read (the service's user, typically).
std::string unreadable_files(const std::string& config_uri) {
  const std::string file = config_file(config_uri);
  if (file.empty()) return {};
  if (std::string bad = unreadable(file); !bad.empty()) {
    return "; cannot read the DDS configuration " + bad;
  }
  std::string causes;
  for (const std::string& path : referenced_files(read_file(file))) {
    if (std::string bad = unreadable(path); !bad.empty()) {
      causes.append("; cannot read ").append(bad).append(", named by ").append(file);
    }
  }
  return causes;
}

// A warning or error for the program's log. The daemon installs its own logger (stderr, in
// the journal); a tool that keeps spdlog's unnamed default logger writes to stdout, which may
// carry its output (swivelctl --json), so there the line goes to stderr instead.
void report(spdlog::level::level_enum level, const std::string& message) {
  if (!spdlog::default_logger()->name().empty()) {
    spdlog::log(level, "{}", message);
    return;
  }
  std::fprintf(stderr, "%s: %s\n", level == spdlog::level::err ? "error" : "warning",
               message.c_str());
}

// Warns when the DDS Security permissions of this participant (make_permissions.sh gives them
// its certificate's validity) expire within kExpiryWarningDays, or have.
constexpr int kExpiryWarningDays = 30;

void warn_if_expiring(const std::string& config_uri) {
  const std::string file = config_file(config_uri);
  if (file.empty() || !unreadable(file).empty()) return;
  static const std::regex permissions_element(R"(<Permissions>\s*file:([^<\s]+)\s*</Permissions>)");
  static const std::regex not_after_element(R"(<not_after>\s*([0-9T:-]+)\s*</not_after>)");
  const std::string xml = read_file(file);
  std::smatch permissions;
  if (!std::regex_search(xml, permissions, permissions_element)) return;
  const std::string document = read_file(permissions[1].str());
  std::smatch not_after;
  if (!std::regex_search(document, not_after, not_after_element)) return;
  std::tm tm{};
  if (::strptime(not_after[1].str().c_str(), "%Y-%m-%dT%H:%M:%S", &tm) == nullptr) return;
  const auto expires = std::chrono::system_clock::from_time_t(::timegm(&tm));
  const auto left =
      std::chrono::duration_cast<std::chrono::hours>(expires - std::chrono::system_clock::now());
  const long days = static_cast<long>(left.count() / 24);
  if (left.count() < 0) {
    report(spdlog::level::err, "DDS Security: the permissions " + permissions[1].str() +
                                   " expired on " + not_after[1].str() +
                                   " UTC: renew the identity and its permissions "
                                   "(services/security/README.md, \"Rotate and revoke\")");
  } else if (days < kExpiryWarningDays) {
    report(spdlog::level::warn,
           "DDS Security: the permissions " + permissions[1].str() +
               " (and, from make_permissions.sh, the identity's certificate) expire on " +
               not_after[1].str() + " UTC, in " + std::to_string(days) +
               " days: renew them before then (services/security/README.md, \"Rotate and "
               "revoke\")");
  }
}

// Cyclone refuses to create a domain twice in one process; the first creator's
// configuration holds for every later participant of that domain in this process.
void ensure_domain(std::uint32_t domain_id, const std::string& config_uri) {
  static std::mutex mutex;
  static std::set<std::uint32_t> created;
  const std::scoped_lock lock(mutex);
  if (created.contains(domain_id)) return;
  const dds_entity_t domain = dds_create_domain(domain_id, config_uri.c_str());
  if (domain < 0 && domain != DDS_RETCODE_PRECONDITION_NOT_MET) {
    check(domain, ("dds_create_domain(" + config_uri + ")").c_str());
  }
  // Kept for the life of the process: deleting it would delete other users' participants.
  created.insert(domain_id);
}

}  // namespace

QosPtr default_qos(int depth) { return make_qos(depth, DDS_RELIABILITY_RELIABLE); }

QosPtr best_effort_qos(int depth) { return make_qos(depth, DDS_RELIABILITY_BEST_EFFORT); }

QosPtr run_samples_qos() {
  return make_qos(kRunSamplesHistoryDepth, DDS_RELIABILITY_RELIABLE, kRunSamplesHistoryDepth);
}

bool uses_dds_security(const std::string& config_uri) {
  const std::string file = config_file(config_uri);
  return !file.empty() && read_file(file).find("<Security>") != std::string::npos;
}

Participant::Participant(const ParticipantOptions& options, const std::string& user_data) {
  install_cyclone_log_sink();
  if (options.domain_id > kMaxSecureDomainId && uses_dds_security(options.config_uri)) {
    throw DdsError("domain " + std::to_string(options.domain_id) +
                   " is outside what DDS Security covers (0.." +
                   std::to_string(kMaxSecureDomainId) +
                   ", the governance's and permissions' id_range), and " +
                   config_file(options.config_uri) + " enables it: use a domain in that range");
  }
  const CycloneErrors errors;
  try {
    if (!options.config_uri.empty()) ensure_domain(options.domain_id, options.config_uri);
  } catch (const DdsError& e) {
    throw DdsError(e.what() + errors.suffix() + unreadable_files(options.config_uri));
  }
  QosPtr qos(dds_create_qos());
  if (!user_data.empty()) dds_qset_userdata(qos.get(), user_data.data(), user_data.size());
  const dds_entity_t handle = dds_create_participant(options.domain_id, qos.get(), nullptr);
  if (handle < 0) {
    throw DdsError(std::string("dds_create_participant(domain ") +
                   std::to_string(options.domain_id) + "): " + dds_strretcode(handle) +
                   errors.suffix() + unreadable_files(options.config_uri));
  }
  handle_ = handle;
  warn_if_expiring(options.config_uri);
}

Participant::~Participant() {
  if (handle_ > 0) dds_delete(handle_);
}

ResolvedConfig resolve_config(const std::string& file_uri) {
  const char* env = std::getenv("CYCLONEDDS_URI");
  if (env != nullptr && *env != '\0') {
    std::string description = std::string("CYCLONEDDS_URI=") + env + " (environment";
    if (!file_uri.empty()) description += "; it overrides dds.config " + file_uri;
    return {"", description + ")"};
  }
  if (!file_uri.empty()) return {file_uri, "dds.config " + file_uri + " (CYCLONEDDS_URI unset)"};
  const std::string loopback = "file://" + shipped_config_file("dds/loopback.xml").string();
  return {loopback, loopback + " (CYCLONEDDS_URI unset)"};
}

std::string tool_config_uri() { return resolve_config().uri; }

std::string describe_tool_config() { return resolve_config().description; }

dds_entity_t create_topic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                          const char* name) {
  const CycloneErrors errors;
  const dds_entity_t topic = dds_create_topic(participant, descriptor, name, nullptr, nullptr);
  if (topic == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY) {
    throw DdsError(std::string("dds_create_topic(") + name + "): " + dds_strretcode(topic) +
                   ": the DDS Security permissions of this participant do not allow topic '" +
                   name +
                   "' (its identity's permissions.xml; services/security/topics.sh lists what "
                   "make_permissions.sh grants)" +
                   errors.suffix());
  }
  if (topic < 0) {
    throw DdsError(std::string("dds_create_topic(") + name + "): " + dds_strretcode(topic) +
                   errors.suffix());
  }
  return topic;
}

}  // namespace swivel::dds
