//! Scan-to-scan matchers (seed 000 sec. 4): icl-paper, icl, icp, plicp.
