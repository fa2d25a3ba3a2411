# Hardens the C++ decoders lcm-gen 1.3.1 writes (run by the lcm-gen command on every generated
# header; -DHEADERS=a.hpp;b.hpp). Its decoders trust two lengths read from the message:
#  - a string's length is checked against the bytes left but not for being < 1: a negative
#    length (one corrupt or hostile UDP packet) makes assign() copy up to 2 GB from past the
#    buffer, a crash;
#  - an array's count is used in resize() before the bytes are checked: a count of 2^31 - 1
#    allocates and zeroes gigabytes before the decode fails.
# Both become a failed decode (-1), which the transport counts as a decode error. Every array
# element takes at least one byte, so a count above the bytes left cannot be valid.
# The count check still lets resize() allocate up to 32 bytes per byte of message (a string is
# 32 bytes in memory, 5 on the wire): a 16 MB event took 548 MB. No message of these types comes
# near 1 MiB (the largest, a pose_t of 11 states, is about 1.5 kB), so decode() refuses a
# message above 1 MiB before reading it: at most 32 MiB for one hostile message.
foreach(header ${HEADERS})
  file(READ ${header} text)
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
         "if(\\1 > maxlen - pos || \\1 < 1) return -1;" text "${text}")
  string(REGEX REPLACE "\n( *)(this->[^\n]*)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
         "\n\\1if(this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;\n\\1\\2.resize(this->\\3);" text "${text}")
  string(REGEX REPLACE "(int [A-Za-z0-9_]+::decode\\(const void \\*buf, int offset, int maxlen\\)\n{\n)"
         "\\1    if(maxlen > 1048576) return -1;  // lcmloc: no message of ours is near 1 MiB\n" text "${text}")
  if(NOT text MATCHES "if\\(maxlen > 1048576\\) return -1;")
    message(FATAL_ERROR "${header}: decode() not bounded (lcm-gen output changed?)")
  endif()
  # A decoder shape this script does not know (another lcm-gen) must not pass unhardened.
  if(text MATCHES "_len_*[A-Za-z0-9_]* > maxlen - pos\\) return -1;")
    message(FATAL_ERROR "${header}: a string length check left unhardened (lcm-gen output changed?)")
  endif()
  file(WRITE ${header} "${text}")
endforeach()
