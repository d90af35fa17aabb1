// Outputs that appear whole or not at all: every write goes to a temporary file in the same
// folder, is checked and synced, then renamed into place, so that a failed write (a full disk) or
// an interrupt leaves neither the file nor a temporary. Transactions commit a command's outputs
// together; interrupted commands remove their temporaries.
#pragma once
#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace microsim {

// Calls write(tmp_path), tmp_path in the folder of path, syncs tmp_path to the disk and renames it
// to path; removes tmp_path and throws RuntimeFailure naming path ("cannot write PATH: why") if
// write throws or left no file. write must itself check what it wrote (write_stream_atomically
// does). Inside an OutputTransaction the rename waits for its commit(). A path naming a device or
// a pipe (/dev/null, /dev/stdout) is written in place: a rename would replace the device itself.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);
// write_atomically through a stream: write(out) fills a binary std::ofstream on the temporary; the
// stream is flushed and closed, and a failure of any write, of the flush or of the close fails
// the output. Every output file of microsim is written by this or write_atomically.
void write_stream_atomically(const std::string& path, const std::function<void(std::ofstream&)>& write);

// All outputs of one command committed together: while a transaction is alive, every
// write_atomically goes to its temporary and is renamed into place only by commit(), after every
// output is written; destroying an uncommitted transaction removes its temporaries. Transactions
// nest: the innermost one opened by the writing thread receives its writes, so that commands run
// at once on several threads (the Python module releases the GIL) keep their outputs apart. A
// thread with no live transaction of its own writes directly. pending() sees every thread's.
class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  // Renames every temporary to its final path, in the order written.
  void commit();
  // Temporary holding `path` if a live transaction wrote it and has not committed yet.
  static std::string pending(const std::string& path);
  // Renames this transaction's files into place now (they are read back by the command), but
  // ties them to the enclosing transaction: it removes them if it ends uncommitted or the
  // process is interrupted, and keeps them once it commits.
  void place_provisionally();
  // A folder the command created for its outputs (mkdir succeeded): removed if the transaction
  // ends uncommitted (when empty: only the command's own files were in it) or the process is
  // interrupted; kept once it commits. Folders are removed deepest first.
  void created_folder(const std::string& path);

 private:
  friend void write_atomically(const std::string&, const std::function<void(const std::string&)>&);
  std::vector<std::pair<std::string, std::string>> files_;  // (temporary, final)
  std::vector<std::string> placed_;   // renamed into place by a nested place_provisionally()
  std::vector<std::string> folders_;  // created_folder(), in the order created
};

// Creates the folder `path` (and its missing parents) for a command's outputs; each folder it
// creates is tied to the innermost live transaction (created_folder), so that a failed or
// interrupted command leaves no empty folder behind. False when it cannot create it.
bool create_output_folder(const std::string& path);

// Temporary files and folders removed if the process is interrupted: install_interrupt_cleanup()
// (called first in main, before any other thread starts) blocks SIGINT, SIGTERM and SIGHUP and
// starts a thread that, on one of them, removes every registered path (a folder with its
// contents), then ends the process by the same signal.
void register_temporary(const std::string& path);
void unregister_temporary(const std::string& path);
void install_interrupt_cleanup();
// The cleanup runs while the other threads go on: one of them can meet the files being removed,
// fail and reach exit before the signal is re-raised. Exit paths call this first: during an
// interrupt it waits for the signal thread to end the process.
void wait_if_interrupted();
// A temporary folder (mkdtemp under TMPDIR, registered), removed with its contents when destroyed.
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::string& prefix);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace microsim
