// Keeps the io library non-empty until its first source lands.
namespace skytrace::io { int placeholder_io_symbol = 0; }
