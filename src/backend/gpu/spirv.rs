//! Our own SPIR-V for the passes, with every float operation marked
//! `NoContraction`.
//!
//! SPIR-V lets a driver fuse a multiply into the add that consumes it
//! (one FMA, one rounding instead of two) unless the operation carries
//! `NoContraction`, and naga, which wgpu uses to translate WGSL, never
//! writes that decoration. lavapipe does not fuse; NVIDIA's compiler does,
//! and also turns `f32(f64(a) * f64(b))` back into an f32 product it then
//! fuses, so on an H100 the frames came out one ULP off the CPU's. So on
//! Vulkan the passes are translated here, with the options wgpu's own
//! translation uses, the decoration is added to every float arithmetic
//! result, and the words go to the driver unchanged (wgpu's passthrough).
//! With the decoration, a plain f32 sum, difference or product rounds
//! correctly and alone, as the CPU's: the passes translated here take
//! their products in f32 and keep f64 for quotients and roots
//! ([`super::shaders::Arithmetic::ExactUncontracted`]).

use naga::back::spv;

/// SPIR-V opcodes (SPIR-V 1.0 specification, section 3.32).
mod op {
    pub const SOURCE_CONTINUED: u16 = 2;
    pub const SOURCE: u16 = 3;
    pub const SOURCE_EXTENSION: u16 = 4;
    pub const NAME: u16 = 5;
    pub const MEMBER_NAME: u16 = 6;
    pub const STRING: u16 = 7;
    pub const LINE: u16 = 8;
    pub const EXTENSION: u16 = 10;
    pub const EXT_INST_IMPORT: u16 = 11;
    pub const MEMORY_MODEL: u16 = 14;
    pub const ENTRY_POINT: u16 = 15;
    pub const EXECUTION_MODE: u16 = 16;
    pub const CAPABILITY: u16 = 17;
    pub const DECORATE: u16 = 71;
    pub const MEMBER_DECORATE: u16 = 72;
    pub const NO_LINE: u16 = 317;
    pub const MODULE_PROCESSED: u16 = 330;
    pub const EXECUTION_MODE_ID: u16 = 331;
    pub const DECORATE_ID: u16 = 332;

    /// Float arithmetic whose result a driver may contract with another
    /// operation: negation, the four operations, remainders, and the
    /// vector and matrix products.
    pub const CONTRACTIBLE: [u16; 12] = [
        127, // OpFNegate
        129, // OpFAdd
        131, // OpFSub
        133, // OpFMul
        136, // OpFDiv
        140, // OpFRem
        141, // OpFMod
        142, // OpVectorTimesScalar
        143, // OpMatrixTimesScalar
        144, // OpVectorTimesMatrix
        145, // OpMatrixTimesVector
        146, // OpMatrixTimesMatrix
    ];
}

/// The `NoContraction` decoration's number.
const NO_CONTRACTION: u32 = 42;
/// Words before the first instruction: magic, version, generator, bound, schema.
const HEADER_WORDS: usize = 5;

/// Translates `source` (a whole pass, validated with `capabilities`) to
/// SPIR-V for the compute entry point `entry`, every float operation
/// marked `NoContraction`. `bindings` are the binding numbers of group
/// 0's layout: wgpu numbers Vulkan's bindings by their rank among them,
/// and so must we. An error is a bug in our shaders: the text.
pub fn compile(
    source: &str,
    entry: &str,
    capabilities: naga::valid::Capabilities,
    bindings: &[u32],
) -> Result<Vec<u32>, String> {
    let module =
        naga::front::wgsl::parse_str(source).map_err(|error| error.emit_to_string(source))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
        .validate(&module)
        .map_err(|error| error.emit_to_string(source))?;
    let options = spv::Options {
        // What wgpu's own translation does: indices clamped, buffers left
        // to the device's robust access (wgpu enables it), workgroup
        // memory zeroed, loops bounded; no debug names.
        flags: spv::WriterFlags::empty(),
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: naga::proc::BoundsCheckPolicy::Restrict,
            buffer: naga::proc::BoundsCheckPolicy::Unchecked,
            image_load: naga::proc::BoundsCheckPolicy::Restrict,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        binding_map: vulkan_bindings(bindings),
        fake_missing_bindings: false,
        ..spv::Options::default()
    };
    let pipeline = spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.to_owned(),
    };
    let words = spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|error| error.to_string())?;
    Ok(without_contraction(&words))
}

/// Where wgpu's Vulkan layer puts each binding of group 0: at its rank
/// among the layout's binding numbers.
fn vulkan_bindings(bindings: &[u32]) -> spv::BindingMap {
    let mut sorted = bindings.to_vec();
    sorted.sort_unstable();
    sorted
        .iter()
        .enumerate()
        .map(|(rank, &binding)| {
            let target = spv::BindingInfo {
                descriptor_set: 0,
                binding: rank as u32,
                binding_array_size: None,
            };
            (naga::ResourceBinding { group: 0, binding }, target)
        })
        .collect()
}

/// One instruction: its opcode and its words, the first included.
fn instructions(words: &[u32]) -> impl Iterator<Item = (u16, &[u32])> {
    let mut at = HEADER_WORDS;
    std::iter::from_fn(move || {
        let first = *words.get(at)?;
        let count = (first >> 16) as usize;
        let instruction = words.get(at..at + count.max(1))?;
        at += count.max(1);
        Some((first as u16, instruction))
    })
}

/// `words` with an `OpDecorate %result NoContraction` for every float
/// operation's result, placed with the module's other annotations (the
/// logical layout puts them after the debug instructions and before the
/// first type).
pub fn without_contraction(words: &[u32]) -> Vec<u32> {
    let decorations: Vec<u32> = instructions(words)
        .filter(|(opcode, instruction)| op::CONTRACTIBLE.contains(opcode) && instruction.len() > 2)
        .flat_map(|(_, instruction)| {
            [
                3 << 16 | u32::from(op::DECORATE),
                instruction[2],
                NO_CONTRACTION,
            ]
        })
        .collect();
    let preamble = [
        op::SOURCE_CONTINUED,
        op::SOURCE,
        op::SOURCE_EXTENSION,
        op::NAME,
        op::MEMBER_NAME,
        op::STRING,
        op::LINE,
        op::EXTENSION,
        op::EXT_INST_IMPORT,
        op::MEMORY_MODEL,
        op::ENTRY_POINT,
        op::EXECUTION_MODE,
        op::CAPABILITY,
        op::DECORATE,
        op::MEMBER_DECORATE,
        op::NO_LINE,
        op::MODULE_PROCESSED,
        op::EXECUTION_MODE_ID,
        op::DECORATE_ID,
    ];
    let first_declaration = HEADER_WORDS
        + instructions(words)
            .take_while(|(opcode, _)| preamble.contains(opcode))
            .map(|(_, instruction)| instruction.len())
            .sum::<usize>();
    let mut out = Vec::with_capacity(words.len() + decorations.len());
    out.extend_from_slice(&words[..first_declaration]);
    out.extend_from_slice(&decorations);
    out.extend_from_slice(&words[first_declaration..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::gpu::shaders::{source, Arithmetic, Entry};

    /// `entry`'s pass with `arithmetic`, compiled with the bindings its
    /// WGSL declares.
    fn compiled(entry: Entry, arithmetic: Arithmetic) -> Vec<u32> {
        let source = source(entry, arithmetic);
        let module = naga::front::wgsl::parse_str(&source).expect("parses");
        let bindings: Vec<u32> = module
            .global_variables
            .iter()
            .filter_map(|(_, global)| global.binding.as_ref().map(|binding| binding.binding))
            .collect();
        compile(&source, entry.name(), arithmetic.capabilities(), &bindings)
            .unwrap_or_else(|error| panic!("{} {arithmetic:?}: {error}", entry.name()))
    }

    /// The ids marked `NoContraction`, and the float results of `words`.
    fn marked_and_float_results(words: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let marked = instructions(words)
            .filter(|(opcode, i)| *opcode == op::DECORATE && i[2] == NO_CONTRACTION)
            .map(|(_, i)| i[1])
            .collect();
        let results = instructions(words)
            .filter(|(opcode, i)| op::CONTRACTIBLE.contains(opcode) && i.len() > 2)
            .map(|(_, i)| i[2])
            .collect();
        (marked, results)
    }

    /// Every pass compiles, with each arithmetic our SPIR-V carries (an
    /// adapter's with f64 and without), every float operation in it is
    /// marked, the marks sit before the first type, and naga reads the
    /// words back.
    #[test]
    fn every_float_operation_of_every_pass_is_marked() {
        let carried = [true, false].map(|f64| Arithmetic::for_adapter(f64, true));
        for (arithmetic, entry) in carried
            .into_iter()
            .flat_map(|arithmetic| Entry::ALL.map(|entry| (arithmetic, entry)))
        {
            let name = format!("{} {arithmetic:?}", entry.name());
            let words = compiled(entry, arithmetic);
            let (mut marked, mut results) = marked_and_float_results(&words);
            assert!(!results.is_empty(), "{name}: no float operation");
            marked.sort_unstable();
            results.sort_unstable();
            assert_eq!(marked, results, "{name}");
            let first_type = instructions(&words)
                .position(|(opcode, _)| (19..=39).contains(&opcode))
                .expect("a type");
            let last_mark = instructions(&words)
                .enumerate()
                .filter(|(_, (opcode, i))| *opcode == op::DECORATE && i[2] == NO_CONTRACTION)
                .map(|(at, _)| at)
                .last()
                .expect("a mark");
            assert!(last_mark < first_type, "{name}");
            naga::front::spv::parse_u8_slice(
                bytemuck::cast_slice(&words),
                &naga::front::spv::Options::default(),
            )
            .unwrap_or_else(|error| panic!("{name}: {error}"));
        }
    }

    #[test]
    fn an_unmarked_module_is_found_out() {
        let words = compiled(Entry::CameraRays, Arithmetic::ExactUncontracted);
        let unmarked: Vec<u32> = instructions(&words)
            .filter(|(opcode, i)| !(*opcode == op::DECORATE && i[2] == NO_CONTRACTION))
            .flat_map(|(_, i)| i.to_vec())
            .collect();
        let unmarked = [&words[..HEADER_WORDS], &unmarked].concat();
        let (marked, results) = marked_and_float_results(&unmarked);
        assert!(marked.is_empty() && !results.is_empty());
        assert_eq!(without_contraction(&unmarked), words);
    }
}
